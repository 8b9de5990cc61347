// SPDX-License-Identifier: MIT
/// @file yield_sets.hpp
/// @brief Quadratic yield sets K = {tau : tau . Y tau <= sigma_Y^2} and the
/// projection P_K in the energy norm ||tau||^2 = (E tau, tau).
///
/// Y is diagonal in the eigenbasis of model.hpp with eigenvalues y_i:
/// 1-D: 1; plane stress: (1/2, 3/2, 3/2); "3d": (0, 3, 3, 3, 3, 3) (the set
/// printed in the paper, 3 s:s <= sigma_Y^2, twice the standard left side);
/// "3d_standard": (0, 3/2, ..., 3/2) (von Mises, (3/2) s:s <= sigma_Y^2).
///
/// **Projection.** P_K sigma minimises (E(tau - sigma), tau - sigma) over K.
/// If sigma is in K it is returned unchanged. Otherwise, in eigen-coordinates
/// z = Q sigma, the KKT conditions give tau_i = z_i/(1 + lambda r_i) with
/// r_i = y_i/e_i and lambda > 0 the root of sum_i y_i tau_i(lambda)^2 =
/// sigma_Y^2; components with y_i = 0 are unchanged.
///
/// **Eigenspaces.** Eigenvectors with equal (e_i, y_i) share the factor
/// 1/(1 + lambda r_i), so the computation works with the orthogonal projectors
/// P_g onto the eigenspaces ("classes") g of the pair (E, Y): 3-D has a
/// volumetric and a deviatoric class, plane stress a "mean" and a "deviatoric"
/// class, 1-D one class. Then tau = sum_g P_g sigma/(1 + lambda r_g), and the
/// scalar equation involves only the squared norms |P_g sigma|^2. For 3-D this
/// is the classical radial return.
///
/// **Scalar equation.** detail::solve_multiplier() solves the general
/// sum_g y_g w_g/(1 + lambda s_g)^2 = sigma_Y^2, w_g = |P_g sigma|^2 (s_g = r_g
/// for P_K; the implicit Perzyna step uses s_g = y_g(1/e_g + beta)). With
/// x_g(lambda) = sqrt(y_g w_g)/(1 + lambda s_g) = h_g/(1/s_g + lambda),
/// phi(lambda) = 1/sigma_Y - 1/||x(lambda)|| is convex and decreasing (the
/// Moré–Sorensen trust-region argument), so Newton's method started at
/// lambda = 0 < root increases monotonically to the root without overshoot.
/// With a single active class (3-D) the first step is exact.
///
/// **Scaling.** To stay finite for any finite data: sigma = M sigmahat with M
/// a power of two (exact), S = M Shat with Shat^2 = max_g y_g |P_g sigmahat|^2,
/// c = sigma_Y/S and t = c lambda, so that 1 + lambda s_g = D_g/c with
/// D_g = c + t s_g. Every formula below is written in these variables and
/// stays bounded as c -> 0 (stresses far outside K) or beta -> infinity.
#pragma once

#include "elasticity.hpp"
#include "model.hpp"
#include "small_matrix.hpp"

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace vpcontact
{

/// Eigenvalues of Y in the order of the rows of eigenbasis<N>().
/// @tparam N Mandel size of the model.
/// @param model The model.
template <int N>
std::array<double, N> yield_eigenvalues(Model model)
{
  if (mandel_size(model) != N)
    throw std::invalid_argument("model: Mandel size does not match the template size N");
  std::array<double, N> y{};
  if constexpr (N == 1)
    y = {1.0};
  else if constexpr (N == 3)
    y = {0.5, 1.5, 1.5};
  else
  {
    const double dev = model == Model::three_d ? 3.0 : 1.5;
    y = {0.0, dev, dev, dev, dev, dev};
  }
  return y;
}

/// The Mandel matrix of Y, so that tau . Y tau is the yield function.
/// @tparam N Mandel size of the model.
/// @param model The model.
template <int N>
std::array<double, N * N> yield_matrix(Model model)
{
  return spectral_matrix<N>(eigenbasis<N>(model), yield_eigenvalues<N>(model));
}

namespace detail
{
/// Add c_0 P_0 + c_1 P_1 to the n x n row-major matrix A, where P_0 has the
/// entries 1/k on its leading k x k block (see YieldSet) and P_1 = I - P_0.
template <int N>
inline void add_classes(const std::array<double, (N == 1 ? 1 : 2)>& c, double* A) noexcept
{
  if constexpr (N == 1)
    A[0] += c[0];
  else
  {
    constexpr int k = N == 6 ? 3 : 2;
    const double block = (c[0] - c[1]) * (1.0 / k);
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b)
        A[a * N + b] += block;
    for (int a = 0; a < N; ++a)
      A[a * N + a] += c[1];
  }
}
} // namespace detail

/// A yield set K = {tau : tau . Y tau <= sigma_Y^2} with the elasticity E that
/// defines the projection metric, in their common eigenbasis.
///
/// For every model the eigenvalue pairs (e_i, y_i) form two classes (one for
/// 1-D): the first eigenvector q_0 (mean/volumetric direction) and the span of
/// the others (deviatoric directions), so P_0 = q_0 q_0^T and P_1 = I - P_0.
/// P_0 x puts the mean of the first k = mean_size diagonal Mandel entries on
/// those entries (k = 3 in 3-D, 2 in plane stress); the kernels use this form,
/// and the constructor checks it against Q.
/// @tparam N Mandel size of the model.
template <int N>
struct YieldSet
{
  /// Number G of eigenspaces (classes) of the pair (E, Y).
  static constexpr int num_classes = N == 1 ? 1 : 2;
  /// Number k of diagonal Mandel entries spanned by q_0.
  static constexpr int mean_size = N == 6 ? 3 : (N == 3 ? 2 : 1);
  /// Eigenbasis (rows) shared by E and Y.
  std::array<double, N * N> Q;
  /// Eigenvalues of E.
  std::array<double, N> e;
  /// Eigenvalues of Y.
  std::array<double, N> y;
  /// Yield stress sigma_Y > 0; +infinity means K is the whole space.
  double sigma_y;
  /// Eigenvalue of E on each class.
  std::array<double, num_classes> class_e;
  /// Eigenvalue of Y on each class.
  std::array<double, num_classes> class_y;
  /// (1 - 16 eps) sigma_Y^2, or -1 when sigma_Y^2 overflows or comes near the
  /// subnormal range: stresses with tau . Y tau <= inside_bound, evaluated
  /// without scaling (see clearly_inside), are in K whatever the rounding.
  double inside_bound = -1.0;

  /// @param elasticity Elastic constants (validated here).
  /// @param yield_stress sigma_Y, > 0; +infinity allowed (never yields).
  /// @throws std::invalid_argument naming `E`, `nu` or `sigma_y`.
  YieldSet(const Elasticity& elasticity, double yield_stress)
      : Q(eigenbasis<N>(elasticity.model)), e(elastic_eigenvalues<N>(elasticity)),
        y(yield_eigenvalues<N>(elasticity.model)), sigma_y(yield_stress)
  {
    if (!(yield_stress > 0.0)) // rejects NaN too
      throw std::invalid_argument("sigma_y: yield stress must be positive, got "
                                  + detail::format(yield_stress));
    for (int g = 0; g < num_classes; ++g)
    {
      class_e[g] = e[g];
      class_y[g] = y[g];
    }
    const double bound
        = (1.0 - 16.0 * std::numeric_limits<double>::epsilon()) * yield_stress * yield_stress;
    if (std::isfinite(bound) && bound >= 1e-290)
      inside_bound = bound;
    for (int i = 1; i < N; ++i)
      if (e[i] != e[1] || y[i] != y[1])
        throw std::logic_error("YieldSet: eigenvalues 1..n-1 of E and Y must coincide");
    for (int a = 0; a < N; ++a)
      if (std::fabs(Q[a] * Q[a] - (a < mean_size ? 1.0 / mean_size : 0.0)) > 1e-15)
        throw std::logic_error("YieldSet: unexpected first eigenvector");
  }

  /// Yield function tau . Y tau (see class_value).
  /// @param tau Mandel vector of length N.
  double value(const double* tau) const noexcept
  {
    return class_value(y[0], N == 1 ? 0.0 : y[N - 1], detail::load<N>(tau));
  }

  /// Cheap sufficient test for x in K: tau . Y tau at most (1 - 16 eps) sigma_Y^2,
  /// evaluated without the power-of-two scaling of the full projection (the
  /// bound keeps clear of overflow and of the subnormal range, so a false
  /// answer only sends x to the full test). NaN gives false.
  /// @param x Mandel vector.
  bool clearly_inside(const detail::Vector<N>& x) const noexcept
  {
    return class_value(y[0], N == 1 ? 0.0 : y[N - 1], x) <= inside_bound;
  }

  /// y_0 |P_0 x|^2 + y_1 |P_1 x|^2 with the mean split off exactly, so that a
  /// large mean part (hydrostatic in 3-D) costs only eps |x| in the other part,
  /// not eps |x|^2 as the quadratic form x . Y x would.
  /// @param y0 Eigenvalue of Y on the mean direction q_0.
  /// @param y1 Eigenvalue of Y on its complement (unused for N = 1).
  /// @param x Mandel vector.
  static double class_value(double y0, double y1, const detail::Vector<N>& x) noexcept
  {
    if constexpr (N == 1)
      return y0 * x[0] * x[0];
    else
    {
      const double m = mean(x);
      double rest = 0.0;
      for (int a = 0; a < N; ++a)
      {
        const double d = x[a] - (a < mean_size ? m : 0.0);
        rest += d * d;
      }
      return y0 > 0.0 ? y1 * rest + y0 * (mean_size * m * m) : y1 * rest;
    }
  }

  /// The mean (x_0 + ... + x_{k-1})/k, so that (P_0 x)_a = mean for a < k.
  /// @param x Mandel vector.
  static double mean(const detail::Vector<N>& x) noexcept
  {
    double sum = 0.0;
    for (int a = 0; a < mean_size; ++a)
      sum += x[a];
    return sum * (1.0 / mean_size);
  }

  /// sum_g coefficient[g] P_g x.
  /// @param coefficient One coefficient per class.
  /// @param x Mandel vector.
  detail::Vector<N> apply(const std::array<double, num_classes>& coefficient,
                          const detail::Vector<N>& x) const noexcept
  {
    detail::Vector<N> out;
    if constexpr (N == 1)
      out[0] = coefficient[0] * x[0];
    else
    {
      const double c = (coefficient[0] - coefficient[1]) * mean(x);
      for (int a = 0; a < N; ++a)
        out[a] = coefficient[1] * x[a] + (a < mean_size ? c : 0.0);
    }
    return out;
  }

  /// Add sum_g coefficient[g] P_g to the n x n row-major matrix A.
  /// @param coefficient One coefficient per class.
  /// @param A Matrix, updated in place.
  void add_to(const std::array<double, num_classes>& coefficient,
              detail::Matrix<N>& A) const noexcept
  {
    detail::add_classes<N>(coefficient, A.data());
  }
};

namespace detail
{

/// floor(log2 x) for a positive finite x (-1023 for subnormal x), without a
/// library call.
inline int binary_exponent(double x) noexcept
{
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return static_cast<int>((bits >> 52) & 0x7ff) - 1023;
}

/// 2^k for -1022 <= k <= 1023, exactly, without a library call.
inline double power_of_two(int k) noexcept
{
  const std::uint64_t bits = static_cast<std::uint64_t>(k + 1023) << 52;
  double x;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}

/// A stress split into its eigenspace components, sigma = M sum_g part[g],
/// with M a power of two chosen so that max_a |sigma_a|/M lies in [1, 2)
/// (M clamped to 2^+-1000 for extreme inputs).
template <int N>
struct Split
{
  static constexpr int G = YieldSet<N>::num_classes;
  /// M.
  double scale = 1.0;
  /// 1/M.
  double inverse_scale = 1.0;
  /// part[g] = P_g sigma/M.
  std::array<Vector<N>, G> part;
  /// |part[g]|^2.
  std::array<double, G> norm2;
  /// sum_g y_g |part[g]|^2 = (sigma . Y sigma)/M^2.
  double yield_value;
};

/// Split sigma into its eigenspace components (see Split).
/// @param set The yield set (defines the classes).
/// @param sigma Mandel vector.
/// @param out The split (output).
template <int N>
inline void split(const YieldSet<N>& set, const Vector<N>& sigma, Split<N>& out) noexcept
{
  double largest = 0.0;
  for (int a = 0; a < N; ++a)
  {
    const double v = std::fabs(sigma[a]);
    largest = v > largest ? v : largest;
  }
  int exponent = largest > 0.0 ? binary_exponent(largest) : 0;
  exponent = exponent < -1000 ? -1000 : (exponent > 1000 ? 1000 : exponent);
  out.scale = power_of_two(exponent);
  out.inverse_scale = power_of_two(-exponent);
  const double inverse = out.inverse_scale;
  if constexpr (N == 1)
  {
    out.part[0][0] = sigma[0] * inverse;
    out.norm2[0] = out.part[0][0] * out.part[0][0];
  }
  else
  {
    constexpr int k = YieldSet<N>::mean_size;
    Vector<N> x;
    for (int a = 0; a < N; ++a)
      x[a] = sigma[a] * inverse;
    const double mean = YieldSet<N>::mean(x);
    double w = 0.0;
    for (int a = 0; a < N; ++a)
    {
      out.part[0][a] = a < k ? mean : 0.0;
      out.part[1][a] = x[a] - out.part[0][a];
      w += out.part[1][a] * out.part[1][a];
    }
    out.norm2[0] = k * mean * mean;
    out.norm2[1] = w;
  }
  out.yield_value = 0.0;
  for (int g = 0; g < Split<N>::G; ++g)
    out.yield_value += set.class_y[g] * out.norm2[g];
}

/// Weights s_g = y_g (1/e_g + beta) of the scalar equation (beta = 0: the
/// projection, s_g = r_g = y_g/e_g) and their reciprocals.
template <int N>
struct Weights
{
  static constexpr int G = YieldSet<N>::num_classes;
  /// s_g.
  std::array<double, G> s;
  /// 1/s_g (0 where y_g = 0).
  std::array<double, G> inverse_s;

  /// @param set The yield set.
  /// @param beta k/mu* >= 0.
  Weights(const YieldSet<N>& set, double beta) noexcept
  {
    for (int g = 0; g < G; ++g)
    {
      s[g] = set.class_y[g] * (1.0 / set.class_e[g] + beta);
      inverse_s[g] = s[g] > 0.0 ? 1.0 / s[g] : 0.0;
    }
  }
};

/// Solution of sum_g y_g |P_g sigma|^2/(1 + lambda s_g)^2 = sigma_Y^2 in the
/// scaled variables of yield_sets.hpp.
template <int N>
struct Multiplier
{
  static constexpr int G = YieldSet<N>::num_classes;
  /// False if sigma is in K (lambda = 0; nothing else is set).
  bool active = false;
  /// c = sigma_Y/(M Shat).
  double c = 0.0;
  /// t = c lambda.
  double t = 0.0;
  /// Shat = max_g sqrt(y_g) |P_g sigma|/M.
  double shat = 0.0;
  /// D_g = c + t s_g = c (1 + lambda s_g) for classes with y_g > 0, else 1.
  std::array<double, G> D{};
  /// 1/D_g.
  std::array<double, G> inverse_D{};
  /// Newton iterations used.
  int iterations = 0;
};

/// Solve the scalar equation of yield_sets.hpp by the monotone Newton method.
/// @param set The yield set (classes, sigma_Y).
/// @param weights The weights s_g.
/// @param split The split stress.
template <int N>
inline Multiplier<N> solve_multiplier(const YieldSet<N>& set, const Weights<N>& weights,
                                      const Split<N>& split) noexcept
{
  constexpr double eps = std::numeric_limits<double>::epsilon();
  constexpr int max_iterations = 60;
  constexpr int G = Split<N>::G;
  const std::array<double, G>& s = weights.s;
  Multiplier<N> m;
  // Inside test without square roots or divisions: sigma . Y sigma <= sigma_Y^2.
  // (sigma_Y/M)^2 may overflow to +inf (inside) or underflow to 0 (tested below).
  const double bound = set.sigma_y * split.inverse_scale;
  if (!(split.yield_value > bound * bound)) // NaN input is passed through
    return m;
  double shat2 = 0.0;
  for (int g = 0; g < G; ++g)
  {
    const double v = set.class_y[g] * split.norm2[g];
    shat2 = v > shat2 ? v : shat2;
  }
  if (!(shat2 > 0.0) || !std::isfinite(shat2))
    return m;
  const double inverse_shat2 = 1.0 / shat2;
  m.shat = std::sqrt(shat2);
  m.c = bound * (m.shat * inverse_shat2);
  std::array<double, G> a2{}; // a_g^2 = y_g |P_g sigmahat|^2/Shat^2, max_g a_g^2 = 1
  double sum_a2 = 0.0, sum_a2s = 0.0;
  int active_classes = 0, single = 0;
  for (int g = 0; g < G; ++g)
  {
    if (set.class_y[g] > 0.0)
    {
      a2[g] = set.class_y[g] * split.norm2[g] * inverse_shat2;
      sum_a2 += a2[g];
      sum_a2s += a2[g] * s[g];
      if (a2[g] > 0.0)
      {
        ++active_classes;
        single = g;
      }
    }
  }
  if (sum_a2 <= m.c * m.c)
    return m; // inside after all (rounding of the test above)
  m.active = true;
  m.iterations = 1;
  double t;
  if (active_classes == 1)
  {
    // Radial return: a_g = 1 and the first Newton step t = (1 - c)/s_g gives D_g = 1.
    t = (1.0 - m.c) * weights.inverse_s[single];
    for (int g = 0; g < G; ++g)
    {
      m.D[g] = set.class_y[g] > 0.0 && g != single ? m.c + t * s[g] : 1.0;
      m.inverse_D[g] = g == single || !(set.class_y[g] > 0.0) ? 1.0 : 1.0 / m.D[g];
    }
    m.t = t;
    return m;
  }

  // First Newton step from t = 0, in a form that stays finite as c -> 0.
  t = (std::sqrt(sum_a2) - m.c) * sum_a2 / sum_a2s;
  for (; m.iterations < max_iterations; ++m.iterations)
  {
    // Here every class is active (G = 2): one division serves both 1/D_g
    // unless D_0 D_1 under- or overflows (the iteration is latency-bound, and
    // a division costs about as much as the rest of the step).
    std::array<double, G> inverse_D;
    if constexpr (G == 2)
    {
      const double D0 = m.c + t * s[0], D1 = m.c + t * s[1];
      const double product = D0 * D1;
      if (std::isnormal(product))
      {
        const double inverse = 1.0 / product;
        inverse_D = {D1 * inverse, D0 * inverse};
      }
      else
        inverse_D = {1.0 / D0, 1.0 / D1};
    }
    else
    {
      for (int g = 0; g < G; ++g)
        inverse_D[g] = 1.0 / (m.c + t * s[g]);
    }
    double rho2 = 0.0, slope = 0.0;
    for (int g = 0; g < G; ++g)
    {
      const double x2 = a2[g] * inverse_D[g] * inverse_D[g];
      rho2 += x2;
      slope += x2 * s[g] * inverse_D[g];
    }
    const double step = (std::sqrt(rho2) - 1.0) * rho2 / slope;
    if (step > 0.0)
      t += step;
    if (!(step > 4.0 * eps * t))
      break;
  }
  m.t = t;
  for (int g = 0; g < G; ++g)
  {
    m.D[g] = set.class_y[g] > 0.0 ? m.c + t * s[g] : 1.0;
    m.inverse_D[g] = 1.0 / m.D[g];
  }
  return m;
}

/// Factor <= 1 for the components with y_g > 0 that moves the projection
/// inside K by a relative margin of 2 eps if rounding left it outside or on
/// the boundary, so that P_K is idempotent in floating point.
template <int N>
inline double boundary_correction(const YieldSet<N>& set, const Split<N>& split,
                                  const Multiplier<N>& m) noexcept
{
  constexpr double target = 1.0 - 2.0 * std::numeric_limits<double>::epsilon();
  const double shat2 = m.shat * m.shat;
  double f = 0.0;
  for (int g = 0; g < Split<N>::G; ++g)
    if (set.class_y[g] > 0.0)
      f += set.class_y[g] * split.norm2[g] / shat2 / (m.D[g] * m.D[g]);
  return f > target * target ? target / std::sqrt(f) : 1.0;
}

} // namespace detail

/// Energy-norm projection P_K of one stress (see yield_sets.hpp).
/// @param set The yield set.
/// @param sigma Mandel vector of length N.
/// @param tau P_K sigma (output, may alias sigma). Equal to sigma bit for bit
/// if sigma is in K.
/// @return Newton iterations used (0 if sigma is in K).
template <int N>
int project(const YieldSet<N>& set, const double* sigma, double* tau) noexcept
{
  const detail::Vector<N> x = detail::load<N>(sigma);
  if (set.clearly_inside(x))
  {
    detail::store(x, tau);
    return 0;
  }
  detail::Split<N> split;
  detail::split<N>(set, x, split);
  const detail::Multiplier<N> m
      = detail::solve_multiplier<N>(set, detail::Weights<N>(set, 0.0), split);
  if (!m.active)
  {
    detail::store(x, tau);
    return 0;
  }
  // Active classes: P_g sigma/(1 + lambda r_g) = (sigma_Y/Shat) part[g]/D_g.
  const double active = set.sigma_y / m.shat * detail::boundary_correction<N>(set, split, m);
  detail::Vector<N> p{};
  for (int g = 0; g < YieldSet<N>::num_classes; ++g)
  {
    const double f = set.class_y[g] > 0.0 ? active * m.inverse_D[g] : split.scale;
    for (int a = 0; a < N; ++a)
      p[a] += f * split.part[g][a];
  }
  detail::store(p, tau);
  return m.iterations;
}

/// Energy-norm projection P_K and its derivative dP_K/dsigma (n x n Mandel,
/// row-major). Outside K, dP_K/dsigma = sum_g q_g P_g - (c/w) U V^T with
/// q_g = c/D_g, U = sum_g r_g P_g sigmahat/D_g^2, V = sum_g y_g P_g sigmahat/D_g^2,
/// w = sum_g y_g r_g |P_g sigmahat|^2/D_g^3. At points of non-differentiability
/// (the boundary of K) the derivative from inside K (the identity) is returned.
/// @param set The yield set.
/// @param sigma Mandel vector of length N.
/// @param tau P_K sigma (output, may alias sigma).
/// @param dtau dP_K/dsigma (output, N x N).
template <int N>
void project_with_derivative(const YieldSet<N>& set, const double* sigma, double* tau,
                             double* dtau) noexcept
{
  constexpr int G = YieldSet<N>::num_classes;
  const detail::Weights<N> weights(set, 0.0);
  const std::array<double, G>& r = weights.s;
  detail::Split<N> split;
  detail::split<N>(set, detail::load<N>(sigma), split);
  const detail::Multiplier<N> m = detail::solve_multiplier<N>(set, weights, split);
  project<N>(set, sigma, tau);
  detail::Matrix<N> A{};
  if (!m.active)
  {
    for (int a = 0; a < N; ++a)
      A[a * N + a] = 1.0;
    detail::store(A, dtau);
    return;
  }
  std::array<double, G> q{};
  detail::Vector<N> U{}, V{};
  double w = 0.0;
  for (int g = 0; g < G; ++g)
  {
    if (set.class_y[g] > 0.0)
    {
      const double Dg = m.D[g];
      q[g] = m.c / Dg;
      w += set.class_y[g] * r[g] * split.norm2[g] / (Dg * Dg * Dg);
      for (int a = 0; a < N; ++a)
      {
        U[a] += r[g] * split.part[g][a] / (Dg * Dg);
        V[a] += set.class_y[g] * split.part[g][a] / (Dg * Dg);
      }
    }
    else
      q[g] = 1.0;
  }
  const double coefficient = m.c / w;
  for (int a = 0; a < N; ++a)
    for (int b = 0; b < N; ++b)
      A[a * N + b] = -coefficient * U[a] * V[b];
  set.add_to(q, A);
  detail::store(A, dtau);
}

/// Project num_points stresses onto K.
/// @param set The yield set.
/// @param num_points Number of points.
/// @param sigma Mandel vectors, num_points x N.
/// @param tau Projections (output, num_points x N, may alias sigma).
template <int N>
void project(const YieldSet<N>& set, std::size_t num_points, const double* sigma, double* tau)
{
  for (std::size_t p = 0; p < num_points; ++p)
    project<N>(set, sigma + p * N, tau + p * N);
}

/// Evaluate the yield function tau . Y tau at num_points stresses.
/// @param model The model.
/// @param num_points Number of points.
/// @param tau Mandel vectors, num_points x N.
/// @param values Yield-function values (output, num_points).
template <int N>
void yield_function(Model model, std::size_t num_points, const double* tau, double* values)
{
  const std::array<double, N> y = yield_eigenvalues<N>(model);
  const double y1 = N == 1 ? 0.0 : y[N - 1];
  for (std::size_t p = 0; p < num_points; ++p)
    values[p] = YieldSet<N>::class_value(y[0], y1, detail::load<N>(tau + p * N));
}

} // namespace vpcontact
