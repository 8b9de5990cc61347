// SPDX-License-Identifier: MIT
/// @file elasticity.hpp
/// @brief Isotropic elasticity tensors E in Mandel form.
///
///     1-D:          E tau = E tau
///     plane stress: (E tau)_ab = E nu/(1-nu^2) (tau11 + tau22) delta_ab + E/(1+nu) tau_ab
///     3-D:          E tau = E nu/((1+nu)(1-2nu)) tr(tau) I + E/(1+nu) tau
///
/// E is diagonal in the eigenbasis of model.hpp with the eigenvalues returned
/// by elastic_eigenvalues().
#pragma once

#include "model.hpp"

#include <array>
#include <stdexcept>
#include <string>

namespace vpcontact
{

/// Isotropic elastic constants of a model.
struct Elasticity
{
  /// The model (fixes d and the plane-stress/3-D formula).
  Model model;
  /// Young's modulus E > 0.
  double young;
  /// Poisson's ratio nu in (-1, 1/2); ignored by Model::uniaxial.
  double poisson;

  /// Check the constants.
  /// @throws std::invalid_argument naming `E` or `nu`.
  void validate() const
  {
    detail::require_positive_finite("E", young);
    if (model != Model::uniaxial && !(poisson > -1.0 && poisson < 0.5))
      throw std::invalid_argument("nu: Poisson's ratio must lie in (-1, 0.5), got "
                                  + detail::format(poisson));
  }
};

/// Eigenvalues of E in the order of the rows of eigenbasis<N>().
/// @tparam N Mandel size of the model.
/// @param elasticity Validated elastic constants.
template <int N>
std::array<double, N> elastic_eigenvalues(const Elasticity& elasticity)
{
  elasticity.validate();
  if (mandel_size(elasticity.model) != N)
    throw std::invalid_argument("model: Mandel size does not match the template size N");
  const double E = elasticity.young;
  const double nu = elasticity.poisson;
  std::array<double, N> e{};
  if constexpr (N == 1)
    e = {E};
  else if constexpr (N == 3)
    e = {E / (1.0 - nu), E / (1.0 + nu), E / (1.0 + nu)};
  else
  {
    const double shear = E / (1.0 + nu);
    e = {E / (1.0 - 2.0 * nu), shear, shear, shear, shear, shear};
  }
  return e;
}

/// The n x n Mandel matrix Q^T diag(values) Q of a tensor that is diagonal in
/// the eigenbasis Q.
/// @tparam N Mandel size.
/// @param Q Eigenbasis (rows), from eigenbasis<N>().
/// @param values Eigenvalues.
template <int N>
std::array<double, N * N> spectral_matrix(const std::array<double, N * N>& Q,
                                          const std::array<double, N>& values)
{
  std::array<double, N * N> C{};
  for (int i = 0; i < N; ++i)
    for (int a = 0; a < N; ++a)
      for (int b = 0; b < N; ++b)
        C[a * N + b] += Q[i * N + a] * values[i] * Q[i * N + b];
  return C;
}

/// The Mandel matrix of E.
/// @tparam N Mandel size of the model.
/// @param elasticity Elastic constants.
/// @throws std::invalid_argument naming `E` or `nu` if they are invalid.
template <int N>
std::array<double, N * N> elasticity_matrix(const Elasticity& elasticity)
{
  return spectral_matrix<N>(eigenbasis<N>(elasticity.model), elastic_eigenvalues<N>(elasticity));
}

} // namespace vpcontact
