// SPDX-License-Identifier: MIT
/// @file viscoplastic_law.hpp
/// @brief The viscoplastic law G of the rate-type model
/// dsigma/dt = E deps/dt + G(sigma, eps), as a user-replaceable concept, with
/// two implementations: LinearG and Perzyna.
///
/// **The ViscoplasticLaw concept.** Any type L with
///
/// @code
///   static constexpr int size;   // Mandel size n (1, 3 or 6)
///   void G(const double* sigma, const double* eps, double* g) const;
///   void dG_dsigma(const double* sigma, const double* eps, double* J) const;
///   void dG_deps(const double* sigma, const double* eps, double* J) const;
/// @endcode
///
/// where all vectors are Mandel vectors of length n and J is an n x n
/// row-major Mandel matrix (the derivative of the Mandel vector of G with
/// respect to the Mandel vector of sigma or eps) can be passed to
/// explicit_update() and implicit_update() in stress_update.hpp; the implicit
/// scheme then solves its local equation by Newton's method with these
/// derivatives. Adding a law therefore needs no change to the solver. The
/// functions must not throw, and must accept outputs that alias no input.
/// is_viscoplastic_law_v<L> checks the signatures at compile time.
#pragma once

#include "elasticity.hpp"
#include "small_matrix.hpp"
#include "yield_sets.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <utility>

namespace vpcontact
{

namespace detail
{
template <class L, class = void>
struct is_viscoplastic_law : std::false_type
{
};

template <class L>
struct is_viscoplastic_law<
    L,
    std::void_t<
        decltype(L::size),
        decltype(std::declval<const L&>().G(
            std::declval<const double*>(), std::declval<const double*>(), std::declval<double*>())),
        decltype(std::declval<const L&>().dG_dsigma(
            std::declval<const double*>(), std::declval<const double*>(), std::declval<double*>())),
        decltype(std::declval<const L&>().dG_deps(std::declval<const double*>(),
                                                  std::declval<const double*>(),
                                                  std::declval<double*>()))>>
    : std::bool_constant<L::size == 1 || L::size == 3 || L::size == 6>
{
};
} // namespace detail

/// True if L models the ViscoplasticLaw concept (see viscoplastic_law.hpp).
template <class L>
inline constexpr bool is_viscoplastic_law_v = detail::is_viscoplastic_law<L>::value;

/// The linear law G(sigma, eps) = a sigma + b eps with scalars a, b (the 1-D
/// example of the paper, Sec. 4.2.1, is a = -1, b = 10).
/// @tparam N Mandel size.
template <int N>
struct LinearG
{
  static constexpr int size = N;
  /// Coefficient of sigma.
  double a;
  /// Coefficient of eps.
  double b;

  /// @param a_ Coefficient of sigma (finite).
  /// @param b_ Coefficient of eps (finite).
  /// @throws std::invalid_argument naming `a` or `b` if not finite.
  LinearG(double a_, double b_) : a(a_), b(b_)
  {
    if (!std::isfinite(a))
      throw std::invalid_argument("a: must be finite, got " + detail::format(a));
    if (!std::isfinite(b))
      throw std::invalid_argument("b: must be finite, got " + detail::format(b));
  }

  /// g = a sigma + b eps.
  void G(const double* sigma, const double* eps, double* g) const noexcept
  {
    for (int i = 0; i < N; ++i)
      g[i] = a * sigma[i] + b * eps[i];
  }

  /// J = a I.
  void dG_dsigma(const double*, const double*, double* J) const noexcept
  {
    for (int i = 0; i < N * N; ++i)
      J[i] = (i % (N + 1) == 0) ? a : 0.0;
  }

  /// J = b I.
  void dG_deps(const double*, const double*, double* J) const noexcept
  {
    for (int i = 0; i < N * N; ++i)
      J[i] = (i % (N + 1) == 0) ? b : 0.0;
  }
};

/// Perzyna's law (paper eq. (20)): G(sigma, eps) = -(1/mu*) E (sigma - P_K sigma),
/// with P_K the energy-norm projection onto the yield set.
/// @tparam N Mandel size.
template <int N>
struct Perzyna
{
  static constexpr int size = N;
  /// The yield set K and the elasticity E.
  YieldSet<N> set;
  /// Viscosity mu* > 0.
  double mu_star;
  /// -e_g/mu* per eigenspace class of E: G = sum_g flow_g P_g (sigma - P_K sigma).
  std::array<double, YieldSet<N>::num_classes> flow;

  /// @param yield_set The yield set (with E).
  /// @param viscosity mu* > 0, finite.
  /// @throws std::invalid_argument naming `mu_star`.
  Perzyna(const YieldSet<N>& yield_set, double viscosity) : set(yield_set), mu_star(viscosity)
  {
    detail::require_positive_finite("mu_star", viscosity);
    for (int c = 0; c < YieldSet<N>::num_classes; ++c)
      flow[c] = -set.class_e[c] / mu_star;
  }

  /// g = -(1/mu*) E (sigma - P_K sigma).
  void G(const double* sigma, const double*, double* g) const noexcept
  {
    detail::Vector<N> tau;
    if (project<N>(set, sigma, tau.data()) == 0) // sigma in K: no viscoplastic flow
    {
      for (int i = 0; i < N; ++i)
        g[i] = 0.0;
      return;
    }
    // E applied per eigenspace of the yield set (E and Y share them): O(n), not O(n^2).
    for (int i = 0; i < N; ++i)
      tau[i] = sigma[i] - tau[i];
    detail::store(set.apply(flow, tau), g);
  }

  /// J = -(1/mu*) E (I - dP_K/dsigma); on the boundary of K the derivative
  /// from inside (zero) is returned.
  void dG_dsigma(const double* sigma, const double*, double* J) const noexcept
  {
    detail::Vector<N> tau;
    detail::Matrix<N> dP;
    project_with_derivative<N>(set, sigma, tau.data(), dP.data());
    for (int i = 0; i < N; ++i)
      dP[i * N + i] -= 1.0; // dP - I
    const detail::Matrix<N> E = spectral_matrix<N>(set.Q, set.e);
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b)
      {
        double sum = 0.0;
        for (int k = 0; k < N; ++k)
          sum += E[a * N + k] * dP[k * N + b];
        J[a * N + b] = sum / mu_star;
      }
  }

  /// J = 0: Perzyna's law does not depend on eps.
  void dG_deps(const double*, const double*, double* J) const noexcept
  {
    for (int i = 0; i < N * N; ++i)
      J[i] = 0.0;
  }
};

static_assert(is_viscoplastic_law_v<LinearG<3>>);
static_assert(is_viscoplastic_law_v<Perzyna<6>>);

} // namespace vpcontact
