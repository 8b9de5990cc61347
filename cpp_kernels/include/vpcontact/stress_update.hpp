// SPDX-License-Identifier: MIT
/// @file stress_update.hpp
/// @brief One time step of dsigma/dt = E deps/dt + G(sigma, eps) at many
/// points, with the derivative (tangent) dsigma_n/deps_n.
///
/// Given sigma_{n-1}, eps_{n-1}, eps_n and k = dt, with the trial stress
/// sigma^tr = sigma_{n-1} + E (eps_n - eps_{n-1}):
///
///  - explicit: sigma_n = sigma^tr + k G(sigma_{n-1}, eps_{n-1}); tangent E.
///  - implicit: sigma_n = sigma^tr + k G(sigma_n, eps_n), solved by Newton's
///    method on R(sigma) = sigma - sigma^tr - k G(sigma, eps_n) with
///    J = I - k dG/dsigma; tangent J^{-1} (E + k dG/deps) (consistent).
///  - linearized (linearly implicit Euler, the rate-tangent method of Peirce,
///    Shih and Needleman): G linearised at the start of the step,
///    J (sigma_n - sigma_{n-1}) = (E + k dG/deps) (eps_n - eps_{n-1})
///    + k G(sigma_{n-1}, eps_{n-1}), J = I - k dG/dsigma there; affine in eps_n
///    with the tangent J^{-1} (E + k dG/deps), fixed within the step. For a law
///    linear in (sigma, eps) it is the implicit step.
///
/// Two laws have exact specialisations of the implicit step:
///
///  - LinearG: sigma_n = (sigma^tr + k b eps_n)/(1 - k a), which requires
///    1 - k a > 0 (otherwise the step reverses the sign of the solution).
///  - Perzyna: with beta = k/mu*, sigma_n = sigma^tr if sigma^tr is in K.
///    Otherwise p = P_K sigma_n satisfies, in eigen-coordinates z = Q sigma^tr,
///    p_i = z_i/(1 + lambda s_i), s_i = y_i (1/e_i + beta), with
///    sum_i y_i p_i^2 = sigma_Y^2 (the scalar equation of yield_sets.hpp), and
///    sigma_n,i = z_i m_i(lambda), m_i = (1 + lambda y_i/e_i)/(1 + lambda s_i).
///    Implicit differentiation gives, with q_i = 1/(1 + lambda s_i),
///    m_i' = -beta y_i q_i^2 and
///    dlambda/dz_j = y_j z_j q_j^2/sum_k y_k s_k z_k^2 q_k^3, the tangent
///    dsigma_n/deps = Q^T (diag(m) + (z o m') (dlambda/dz)^T) diag(e) Q.
///    The kernel evaluates this per eigenspace (sigma_n = sum_g m_g P_g
///    sigma^tr; 3-D is a radial return) in the scaled variables of
///    yield_sets.hpp, so it stays finite and bounded as k E/mu* -> infinity.
///    In that rate-independent limit sigma^tr - sigma_n lies in the normal cone
///    of K: sigma_n tends to the point of K closest to sigma^tr in the Frobenius
///    norm, which is P_K sigma^tr for 1-D and 3-D (radial return) but not for
///    plane stress (E has two eigenvalues on the constrained components).
///
/// All array loops read a point's inputs before writing its outputs, so the
/// output arrays may alias the inputs, and allocate nothing.
#pragma once

#include "elasticity.hpp"
#include "small_matrix.hpp"
#include "viscoplastic_law.hpp"
#include "yield_sets.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace vpcontact
{

/// Mandel arrays of one time step at num_points points (all row-major).
struct StepArrays
{
  /// Number of points.
  std::size_t num_points;
  /// sigma_{n-1}, num_points x n.
  const double* sigma_old;
  /// eps_{n-1}, num_points x n.
  const double* eps_old;
  /// eps_n, num_points x n.
  const double* eps_new;
  /// sigma_n (output), num_points x n.
  double* sigma_new;
  /// dsigma_n/deps_n (output), num_points x n x n; nullptr to skip.
  double* tangent;
};

/// Controls of the local Newton iteration of the generic implicit step.
struct NewtonOptions
{
  /// Stop when the Newton correction is <= rtol * max(|sigma|, |sigma^tr|),
  /// or when corrections below 1e-8 of that scale stop contracting (the
  /// rounding floor of an ill-conditioned law).
  double rtol = 1e-14;
  /// Maximum number of iterations before std::runtime_error is thrown.
  int max_iterations = 50;
};

namespace detail
{
/// Index of the first non-finite entry of x[0..count), or count if all are
/// finite. A double is inf or NaN exactly when its exponent field is all ones,
/// i.e. when adding one unit of the exponent field carries into the sign bit;
/// OR-ing those sums over a block is integer work the compiler vectorises, so
/// the scan runs at a couple of instructions per entry. Only a block with a
/// non-finite entry is searched element by element.
inline std::size_t first_non_finite(const double* x, std::size_t count) noexcept
{
  constexpr std::size_t block = 512;
  constexpr std::uint64_t exponent = 0x7ff0000000000000ULL, unit = 0x0010000000000000ULL;
  for (std::size_t start = 0; start < count; start += block)
  {
    const std::size_t end = std::min(count, start + block);
    std::uint64_t flags = 0;
    for (std::size_t i = start; i < end; ++i)
    {
      std::uint64_t bits;
      std::memcpy(&bits, x + i, sizeof bits);
      flags |= (bits & exponent) + unit;
    }
    if (flags >> 63)
      for (std::size_t i = start; i < end; ++i)
        if (!std::isfinite(x[i]))
          return i;
  }
  return count;
}

/// The checks every stress update starts with: k > 0 finite, and finite
/// inputs (std::invalid_argument naming the array and the first bad point).
template <int N>
inline void check_step(double dt, const StepArrays& step)
{
  require_positive_finite("dt", dt);
  const std::pair<const char*, const double*> inputs[]
      = {{"sigma_old", step.sigma_old}, {"eps_old", step.eps_old}, {"eps_new", step.eps_new}};
  for (const auto& [name, x] : inputs)
  {
    const std::size_t i = first_non_finite(x, step.num_points * N);
    if (i < step.num_points * N)
      throw std::invalid_argument(std::string(name) + ": contains non-finite values (first at point "
                                  + std::to_string(i / N) + ")");
  }
}

/// Whether every entry of x is finite (a sum of x_i - x_i is 0, or NaN if one is +-inf or NaN).
template <int N>
inline bool all_finite(const Vector<N>& x) noexcept
{
  double sum = 0.0;
  for (int i = 0; i < N; ++i)
    sum += x[i] - x[i];
  return sum == 0.0;
}

[[noreturn]] inline void throw_non_finite_trial(std::size_t p)
{
  throw std::domain_error("stress update: the trial stress sigma_old + E (eps_new - eps_old)"
                          " is not finite at point "
                          + std::to_string(p));
}

/// sigma^tr = sigma_old + C (eps_new - eps_old) at point p, checked finite.
template <int N>
inline Vector<N> trial_stress(const Matrix<N>& C, const StepArrays& step, std::size_t p,
                              Vector<N>& eps_new)
{
  const Vector<N> so = load<N>(step.sigma_old + p * N);
  Vector<N> de = load<N>(step.eps_old + p * N);
  eps_new = load<N>(step.eps_new + p * N);
  for (int i = 0; i < N; ++i)
    de[i] = eps_new[i] - de[i];
  Vector<N> tr = multiply<N>(C, de);
  double not_finite = 0.0;
  for (int i = 0; i < N; ++i)
  {
    tr[i] += so[i];
    not_finite += tr[i] - tr[i]; // 0, or NaN if tr[i] is +-inf or NaN
  }
  if (!(not_finite == 0.0))
    throw_non_finite_trial(p);
  return tr;
}

/// Whether the rate equation's elasticity is the one of the yield set (then E
/// can be applied by eigenspace classes).
template <int N>
inline bool same_elasticity(const YieldSet<N>& set, const Elasticity& elasticity)
{
  return elastic_eigenvalues<N>(elasticity) == set.e && eigenbasis<N>(elasticity.model) == set.Q;
}

/// sigma^tr = sigma_old + E (eps_new - eps_old) at point p, with E applied by
/// the eigenspace classes of the yield set (O(n)); not checked finite.
template <int N>
inline Vector<N> trial_stress_by_classes(const YieldSet<N>& set, const StepArrays& step,
                                         std::size_t p) noexcept
{
  const Vector<N> eo = load<N>(step.eps_old + p * N);
  const Vector<N> en = load<N>(step.eps_new + p * N);
  Vector<N> de;
  for (int a = 0; a < N; ++a)
    de[a] = en[a] - eo[a];
  Vector<N> tr = set.apply(set.class_e, de);
  for (int a = 0; a < N; ++a)
    tr[a] += step.sigma_old[p * N + a];
  return tr;
}

/// T = coefficient U V^T + sum_g me_g P_g, written to T (n x n, row-major).
template <int N>
inline void rank_one_plus_classes(double coefficient, const Vector<N>& U, const Vector<N>& V,
                                  const std::array<double, YieldSet<N>::num_classes>& me,
                                  double* T) noexcept
{
  for (int a = 0; a < N; ++a)
  {
    const double ua = coefficient * U[a];
    for (int b = 0; b < N; ++b)
      T[a * N + b] = ua * V[b];
  }
  add_classes<N>(me, T);
}

/// The matrices of a step linearised at (sigma, eps): A = I - k dG/dsigma (LU
/// factors) and B = C + k dG/deps, so that dsigma_n = A^{-1} B deps_n.
template <int N>
struct StepMatrices
{
  Matrix<N> A, B;
  std::array<int, N> perm;

  /// @throws std::domain_error naming `who` and the point if A is singular.
  template <class Law>
  StepMatrices(const Law& law, double dt, const Matrix<N>& C, const Vector<N>& sigma,
               const Vector<N>& eps, const char* who, std::size_t point)
  {
    law.dG_dsigma(sigma.data(), eps.data(), A.data());
    for (int i = 0; i < N * N; ++i)
      A[i] = (i % (N + 1) == 0 ? 1.0 : 0.0) - dt * A[i];
    if (!lu_factor<N>(A, perm))
      throw std::domain_error(std::string(who) + ": I - dt dG/dsigma is singular at point "
                              + std::to_string(point));
    law.dG_deps(sigma.data(), eps.data(), B.data());
    for (int i = 0; i < N * N; ++i)
      B[i] = C[i] + dt * B[i];
  }
};

template <std::size_t M>
inline void store_if(const std::array<double, M>& x, double* p, std::size_t offset) noexcept
{
  if (p)
    store(x, p + offset);
}
} // namespace detail

/// Explicit step sigma_n = sigma_{n-1} + E (eps_n - eps_{n-1})
/// + k G(sigma_{n-1}, eps_{n-1}); tangent E.
/// @tparam Law A ViscoplasticLaw (see viscoplastic_law.hpp).
/// @param law The law G.
/// @param elasticity Elastic constants of the rate equation.
/// @param dt Time step k > 0.
/// @param step The arrays.
/// @throws std::invalid_argument naming `E`, `nu`, `model` or `dt`;
/// std::domain_error if the trial stress or the result overflows.
template <class Law>
void explicit_update(const Law& law, const Elasticity& elasticity, double dt,
                     const StepArrays& step)
{
  static_assert(is_viscoplastic_law_v<Law>, "Law must model the ViscoplasticLaw concept");
  constexpr int N = Law::size;
  detail::check_step<N>(dt, step);
  const detail::Matrix<N> C = elasticity_matrix<N>(elasticity);
  for (std::size_t p = 0; p < step.num_points; ++p)
  {
    detail::Vector<N> en;
    detail::Vector<N> s = detail::trial_stress<N>(C, step, p, en);
    const detail::Vector<N> so = detail::load<N>(step.sigma_old + p * N);
    const detail::Vector<N> eo = detail::load<N>(step.eps_old + p * N);
    detail::Vector<N> g;
    law.G(so.data(), eo.data(), g.data());
    double not_finite = 0.0;
    for (int i = 0; i < N; ++i)
    {
      s[i] += dt * g[i];
      not_finite += s[i] - s[i]; // 0, or NaN if s[i] is +-inf or NaN
    }
    if (!(not_finite == 0.0))
      throw std::domain_error("explicit_update: sigma_new is not finite at point "
                              + std::to_string(p) + " (dt G(sigma_old, eps_old) overflows)");
    detail::store(s, step.sigma_new + p * N);
    detail::store_if(C, step.tangent, p * N * N);
  }
}

/// Explicit step for Perzyna's law: as the generic one, with E applied by
/// eigenspace classes (O(n)) when the rate equation's elasticity is the yield
/// set's, and no flow at points of K (the common, elastic case).
template <int N>
void explicit_update(const Perzyna<N>& law, const Elasticity& elasticity, double dt,
                     const StepArrays& step)
{
  const YieldSet<N>& set = law.set;
  if (!detail::same_elasticity<N>(set, elasticity))
  {
    explicit_update<Perzyna<N>>(law, elasticity, dt, step);
    return;
  }
  detail::check_step<N>(dt, step);
  const detail::Matrix<N> C = elasticity_matrix<N>(elasticity);
  for (std::size_t p = 0; p < step.num_points; ++p)
  {
    detail::Vector<N> s = detail::trial_stress_by_classes<N>(set, step, p);
    if (!detail::all_finite<N>(s))
      detail::throw_non_finite_trial(p);
    double not_finite = 0.0;
    const detail::Vector<N> so = detail::load<N>(step.sigma_old + p * N);
    if (!set.clearly_inside(so))
    {
      detail::Vector<N> g;
      law.G(so.data(), step.eps_old + p * N, g.data());
      for (int a = 0; a < N; ++a)
      {
        s[a] += dt * g[a];
        not_finite += s[a] - s[a];
      }
      if (!(not_finite == 0.0))
        throw std::domain_error("explicit_update: sigma_new is not finite at point "
                                + std::to_string(p) + " (dt G(sigma_old, eps_old) overflows)");
    }
    detail::store(s, step.sigma_new + p * N);
    detail::store_if(C, step.tangent, p * N * N);
  }
}

namespace detail
{
/// Solve R(sigma) = sigma - sigma^tr - kappa G(sigma, eps_n) = 0 by Newton's
/// method with backtracking on |R| (needed for laws that are only piecewise
/// smooth, such as Perzyna's at the boundary of K).
/// @param law The law.
/// @param kappa Time step.
/// @param tr sigma^tr.
/// @param en eps_n.
/// @param s Initial guess; the solution on return.
/// @param options Tolerances.
/// @return Whether the iteration converged.
template <class Law>
bool newton_solve(const Law& law, double kappa, const Vector<Law::size>& tr,
                  const Vector<Law::size>& en, Vector<Law::size>& s, const NewtonOptions& options)
{
  constexpr int N = Law::size;
  const double tr_norm = norm<N>(tr);
  Vector<N> g;
  auto residual = [&](const Vector<N>& x, Vector<N>& r)
  {
    law.G(x.data(), en.data(), g.data());
    for (int i = 0; i < N; ++i)
      r[i] = x[i] - tr[i] - kappa * g[i];
    return norm<N>(r);
  };
  Vector<N> r;
  double r_norm = residual(s, r);
  if (r_norm == 0.0)
    return true;
  double previous_ds_norm = std::numeric_limits<double>::infinity();
  for (int it = 0; it < options.max_iterations; ++it)
  {
    Matrix<N> A;
    std::array<int, N> perm;
    law.dG_dsigma(s.data(), en.data(), A.data());
    for (int i = 0; i < N * N; ++i)
      A[i] = (i % (N + 1) == 0 ? 1.0 : 0.0) - kappa * A[i];
    if (!lu_factor<N>(A, perm))
      return false;
    const Vector<N> ds = lu_solve<N>(A, perm, r);
    const double ds_norm = norm<N>(ds);
    if (!std::isfinite(ds_norm))
      return false;
    // Converged: a tiny correction, or corrections that no longer contract
    // while already small (the rounding floor of an ill-conditioned law).
    const double scale = std::fmax(norm<N>(s), tr_norm);
    const bool stalled = ds_norm <= 1e-8 * scale && ds_norm >= 0.5 * previous_ds_norm;
    previous_ds_norm = ds_norm;
    if (ds_norm <= options.rtol * scale || stalled)
    {
      for (int i = 0; i < N; ++i)
        s[i] -= ds[i];
      return true;
    }
    double alpha = 1.0;
    Vector<N> trial, r_trial;
    for (;;)
    {
      for (int i = 0; i < N; ++i)
        trial[i] = s[i] - alpha * ds[i];
      const double trial_norm = residual(trial, r_trial);
      if (trial_norm < (1.0 - 1e-4 * alpha) * r_norm || alpha < 1e-3)
      {
        r_norm = trial_norm;
        break;
      }
      alpha *= 0.5;
    }
    s = trial;
    r = r_trial;
    if (r_norm == 0.0)
      return true;
  }
  return false;
}
} // namespace detail

/// Implicit step solved by Newton's method with the law's derivatives (works
/// for any ViscoplasticLaw); the tangent is J^{-1} (E + k dG/deps) with
/// J = I - k dG/dsigma at the solution. Newton starts from sigma^tr; if it
/// fails (a stiff, nonsmooth law), the step is reached by continuation in the
/// time step, kappa = k 2^-m, k 2^(1-m), ..., k, each solve starting from the
/// previous solution, for m = 4, 8, ..., 32.
/// @tparam Law A ViscoplasticLaw.
/// @param law The law G.
/// @param elasticity Elastic constants of the rate equation.
/// @param dt Time step k > 0.
/// @param step The arrays.
/// @param options Newton tolerances.
/// @throws std::invalid_argument naming `E`, `nu`, `model` or `dt`;
/// std::domain_error if I - k dG/dsigma is singular at the solution;
/// std::runtime_error if Newton's method does not converge.
template <class Law>
void implicit_update_newton(const Law& law, const Elasticity& elasticity, double dt,
                            const StepArrays& step, const NewtonOptions& options = {})
{
  static_assert(is_viscoplastic_law_v<Law>, "Law must model the ViscoplasticLaw concept");
  constexpr int N = Law::size;
  detail::check_step<N>(dt, step);
  const detail::Matrix<N> C = elasticity_matrix<N>(elasticity);
  for (std::size_t p = 0; p < step.num_points; ++p)
  {
    detail::Vector<N> en;
    const detail::Vector<N> tr = detail::trial_stress<N>(C, step, p, en);
    detail::Vector<N> s = tr;
    bool converged = detail::newton_solve(law, dt, tr, en, s, options);
    for (int m = 4; !converged && m <= 32; m += 4)
    {
      s = tr;
      converged = true;
      for (int j = m; converged && j >= 0; --j)
        converged = detail::newton_solve(law, std::ldexp(dt, -j), tr, en, s, options);
    }
    if (!converged)
      throw std::runtime_error("implicit_update: local Newton iteration did not converge at point "
                               + std::to_string(p));
    detail::store(s, step.sigma_new + p * N);
    if (step.tangent)
    {
      const detail::StepMatrices<N> m(law, dt, C, s, en, "implicit_update", p);
      detail::store(detail::lu_solve_matrix<N>(m.A, m.perm, m.B), step.tangent + p * N * N);
    }
  }
}

namespace detail
{
/// The linearly implicit step at point p (see linearized_update()).
template <class Law, int N = Law::size>
void linearized_point(const Law& law, double dt, const Matrix<N>& C, const StepArrays& step,
                      std::size_t p)
{
  Vector<N> en;
  (void)trial_stress<N>(C, step, p, en); // checks sigma^tr finite
  const Vector<N> so = load<N>(step.sigma_old + p * N);
  const Vector<N> eo = load<N>(step.eps_old + p * N);
  const StepMatrices<N> m(law, dt, C, so, eo, "linearized_update", p);
  Vector<N> g, rhs;
  law.G(so.data(), eo.data(), g.data());
  for (int i = 0; i < N; ++i)
  {
    double sum = dt * g[i];
    for (int j = 0; j < N; ++j)
      sum += m.B[i * N + j] * (en[j] - eo[j]);
    rhs[i] = sum;
  }
  const Vector<N> ds = lu_solve<N>(m.A, m.perm, rhs);
  Vector<N> s;
  for (int i = 0; i < N; ++i)
    s[i] = so[i] + ds[i];
  if (!all_finite<N>(s))
    throw std::domain_error("linearized_update: sigma_new is not finite at point "
                            + std::to_string(p));
  store(s, step.sigma_new + p * N);
  if (step.tangent)
    store(lu_solve_matrix<N>(m.A, m.perm, m.B), step.tangent + p * N * N);
}
} // namespace detail

/// Linearly implicit step (see the file documentation): one linear solve per
/// point with the law's derivatives at (sigma_{n-1}, eps_{n-1}); affine in
/// eps_n, so a body's step is linear in u (no constitutive Newton iteration).
/// @tparam Law A ViscoplasticLaw.
/// @param law The law G.
/// @param elasticity Elastic constants of the rate equation.
/// @param dt Time step k > 0.
/// @param step The arrays.
/// @throws std::invalid_argument naming `E`, `nu`, `model` or `dt`;
/// std::domain_error if the trial stress or the result is not finite, or if
/// I - k dG/dsigma is singular at a point.
template <class Law>
void linearized_update(const Law& law, const Elasticity& elasticity, double dt,
                       const StepArrays& step)
{
  static_assert(is_viscoplastic_law_v<Law>, "Law must model the ViscoplasticLaw concept");
  constexpr int N = Law::size;
  detail::check_step<N>(dt, step);
  const detail::Matrix<N> C = elasticity_matrix<N>(elasticity);
  for (std::size_t p = 0; p < step.num_points; ++p)
    detail::linearized_point(law, dt, C, step, p);
}

/// Relative width of the band around the yield surface, in the yield function
/// tau . Y tau / sigma_Y^2, whose points the linearized Perzyna step treats as
/// in K (see linearized_update()).
inline constexpr double linearized_yield_band = 1e-8;

/// Linearly implicit step for Perzyna's law: as the generic one, with the
/// elastic step (sigma^tr, tangent E) at points whose sigma_{n-1} lies in K,
/// where G and its derivative vanish — or lies outside it by less than
/// linearized_yield_band. The step's tangent jumps at the yield surface (E
/// inside, the soft plastic tangent outside); a stress that reached the surface
/// at the end of the last step lies on either side of it by round-off and
/// solver tolerance, so without the band mathematically equal stresses (a
/// homogeneous state at several quadrature points) took different tangents and
/// the solution lost its symmetry (README, "Design notes"). G there is of the
/// band's size.
template <int N>
void linearized_update(const Perzyna<N>& law, const Elasticity& elasticity, double dt,
                       const StepArrays& step)
{
  detail::check_step<N>(dt, step);
  const detail::Matrix<N> C = elasticity_matrix<N>(elasticity);
  // (only where sigma_Y^2 neither overflows nor comes near the subnormal range: inside_bound)
  const double banded = law.set.inside_bound > 0.0
                            ? (1.0 + linearized_yield_band) * law.set.sigma_y * law.set.sigma_y
                            : -1.0;
  for (std::size_t p = 0; p < step.num_points; ++p)
  {
    const detail::Vector<N> so = detail::load<N>(step.sigma_old + p * N);
    detail::Vector<N> tau;
    if (law.set.clearly_inside(so) || law.set.value(so.data()) <= banded
        || project<N>(law.set, so.data(), tau.data()) == 0)
    {
      detail::Vector<N> en;
      detail::store(detail::trial_stress<N>(C, step, p, en), step.sigma_new + p * N);
      detail::store_if(C, step.tangent, p * N * N);
    }
    else
      detail::linearized_point(law, dt, C, step, p);
  }
}

/// Implicit step for any ViscoplasticLaw: Newton's method (see
/// implicit_update_newton()); LinearG and Perzyna have exact overloads below.
template <class Law>
void implicit_update(const Law& law, const Elasticity& elasticity, double dt,
                     const StepArrays& step)
{
  implicit_update_newton(law, elasticity, dt, step);
}

/// Implicit step for LinearG in closed form:
/// sigma_n = (sigma^tr + k b eps_n)/(1 - k a), tangent (E + k b I)/(1 - k a).
/// @param law The law.
/// @param elasticity Elastic constants.
/// @param dt Time step k > 0 with 1 - k a > 0.
/// @param step The arrays.
/// @throws std::invalid_argument naming `dt` (or `E`, `nu`, `model`).
template <int N>
void implicit_update(const LinearG<N>& law, const Elasticity& elasticity, double dt,
                     const StepArrays& step)
{
  detail::check_step<N>(dt, step);
  const double denominator = 1.0 - dt * law.a;
  if (!(denominator > 0.0))
    throw std::invalid_argument("dt: the implicit step of G = a sigma + b eps needs "
                                "1 - dt*a > 0, got dt*a = "
                                + detail::format(dt * law.a));
  const detail::Matrix<N> C = elasticity_matrix<N>(elasticity);
  detail::Matrix<N> T = C;
  for (int i = 0; i < N * N; ++i)
    T[i] = (C[i] + (i % (N + 1) == 0 ? dt * law.b : 0.0)) / denominator;
  for (std::size_t p = 0; p < step.num_points; ++p)
  {
    detail::Vector<N> en;
    detail::Vector<N> s = detail::trial_stress<N>(C, step, p, en);
    double not_finite = 0.0;
    for (int i = 0; i < N; ++i)
    {
      s[i] = (s[i] + dt * law.b * en[i]) / denominator;
      not_finite += s[i] - s[i]; // 0, or NaN if s[i] is +-inf or NaN
    }
    if (!(not_finite == 0.0))
      throw std::domain_error("implicit_update: sigma_new is not finite at point "
                              + std::to_string(p) + " (1 - dt*a too small?)");
    detail::store(s, step.sigma_new + p * N);
    detail::store_if(T, step.tangent, p * N * N);
  }
}

/// Implicit step for Perzyna's law, exact up to the scalar equation (see the
/// file documentation), with its consistent tangent. If `elasticity` differs
/// from the elasticity of the law's yield set the generic Newton step is used.
/// @param law The law.
/// @param elasticity Elastic constants of the rate equation.
/// @param dt Time step k > 0.
/// @param step The arrays.
/// @throws std::invalid_argument naming `dt` (or `E`, `nu`, `model`).
template <int N>
void implicit_update(const Perzyna<N>& law, const Elasticity& elasticity, double dt,
                     const StepArrays& step)
{
  detail::check_step<N>(dt, step);
  const YieldSet<N>& set = law.set;
  if (!detail::same_elasticity<N>(set, elasticity))
  {
    implicit_update_newton(law, elasticity, dt, step);
    return;
  }
  const double beta = dt / law.mu_star;
  if (!std::isfinite(beta))
    throw std::invalid_argument("dt: dt/mu_star overflows, got dt = " + detail::format(dt));
  constexpr int G = YieldSet<N>::num_classes;
  const detail::Weights<N> weights(set, beta);
  const detail::Matrix<N> C = elasticity_matrix<N>(elasticity); // the elastic points' tangent
  std::array<double, G> r, r_over_beta;
  for (int g = 0; g < G; ++g)
  {
    r[g] = set.class_y[g] / set.class_e[g];
    r_over_beta[g] = r[g] / beta;
  }
  bool try_inside = true;
  for (std::size_t p = 0; p < step.num_points; ++p)
  {
    const detail::Vector<N> tr = detail::trial_stress_by_classes<N>(set, step, p);
    // Elastic points (the common case) skip the scaled split after the cheap inside test; the
    // test is left out after a plastic point, since neighbouring points tend to share their
    // branch (the full path below gives elastic points the same result, bit for bit).
    if (try_inside && set.clearly_inside(tr))
    {
      detail::store(tr, step.sigma_new + p * N);
      detail::store_if(C, step.tangent, p * N * N);
      continue;
    }
    detail::Split<N> split;
    detail::split<N>(set, tr, split);
    if (!std::isfinite(split.yield_value)) // bounded unless tr has an inf or NaN
      detail::throw_non_finite_trial(p);
    const detail::Multiplier<N> m = detail::solve_multiplier<N>(set, weights, split);
    try_inside = !m.active;
    if (!m.active)
    {
      detail::store(tr, step.sigma_new + p * N);
      detail::store_if(C, step.tangent, p * N * N);
      continue;
    }
    // Per class: m_g = (c + t r_g)/D_g; sigma_n = M sum_g m_g part[g].
    // Tangent: sum_g m_g e_g P_g - (c/w) U V^T with U = sum_g y_g part[g]/D_g^2,
    // V = sum_g e_g y_g part[g]/D_g^2, w = sum_g y_g (r_g/beta + y_g) |part[g]|^2/D_g^3.
    detail::Vector<N> sn{}, U{}, V{};
    std::array<double, G> me;
    double w = 0.0;
    for (int g = 0; g < G; ++g)
    {
      double mult = 1.0;
      if (set.class_y[g] > 0.0)
      {
        const double inverse_D = m.inverse_D[g];
        mult = (m.c + m.t * r[g]) * inverse_D;
        const double u = set.class_y[g] * inverse_D * inverse_D;
        const double v = set.class_e[g] * u;
        w += u * (r_over_beta[g] + set.class_y[g]) * split.norm2[g] * inverse_D;
        for (int a = 0; a < N; ++a)
        {
          U[a] += u * split.part[g][a];
          V[a] += v * split.part[g][a];
        }
      }
      me[g] = mult * set.class_e[g];
      const double ms = mult * split.scale;
      for (int a = 0; a < N; ++a)
        sn[a] += ms * split.part[g][a];
    }
    detail::store(sn, step.sigma_new + p * N);
    if (step.tangent)
      detail::rank_one_plus_classes<N>(-m.c / w, U, V, me, step.tangent + p * N * N);
  }
}

} // namespace vpcontact
