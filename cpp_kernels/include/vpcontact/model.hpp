// SPDX-License-Identifier: MIT
/// @file model.hpp
/// @brief The constitutive models, their sizes, and the eigenbasis shared by
/// the elasticity tensor E and the yield-set matrix Y.
///
/// Every model pairs an isotropic elasticity tensor E with a quadratic yield
/// set K = {tau : tau . Y tau <= sigma_Y^2}. For all models E and Y are
/// diagonal in one orthonormal basis of the Mandel space (see mandel.hpp):
///
/// | model              | eigenvector (Mandel)        |  e = eig(E)  | y = eig(Y) |
/// |--------------------|-----------------------------|--------------|------------|
/// | uniaxial ("1d")    | [1]                         | E            | 1          |
/// | plane_stress       | (1, 1, 0)/sqrt2             | E/(1-nu)     | 1/2        |
/// |                    | (1,-1, 0)/sqrt2, (0, 0, 1)  | E/(1+nu)     | 3/2        |
/// | three_d(_standard) | (1, 1, 1, 0, 0, 0)/sqrt3    | E/(1-2nu)    | 0          |
/// |                    | (1,-1, 0, 0, 0, 0)/sqrt2,   |              |            |
/// |                    | (1, 1,-2, 0, 0, 0)/sqrt6,   | E/(1+nu)     | 3 (3/2)    |
/// |                    | three shear unit vectors    |              |            |
///
/// This is what makes the projections and the stress updates cheap: in
/// eigen-coordinates they reduce to one scalar equation.
#pragma once

#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace vpcontact
{

namespace detail
{
/// A double formatted with full precision, for error messages.
inline std::string format(double value)
{
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

/// Throw std::invalid_argument naming `name` unless value is finite and > 0.
inline void require_positive_finite(const char* name, double value)
{
  if (!(std::isfinite(value) && value > 0.0))
    throw std::invalid_argument(std::string(name) + ": must be positive and finite, got "
                                + format(value));
}
} // namespace detail

/// The four constitutive models.
enum class Model
{
  /// One-dimensional (bar) model, Mandel size 1: |tau| <= sigma_Y.
  uniaxial,
  /// Plane stress: tau11^2 + tau22^2 - tau11 tau22 + 3 tau12^2 <= sigma_Y^2.
  plane_stress,
  /// 3-D von Mises set as printed in the paper (Sec. 4.1.2):
  /// (tau11-tau22)^2 + (tau22-tau33)^2 + (tau33-tau11)^2
  ///   + 6 (tau12^2 + tau13^2 + tau23^2) <= sigma_Y^2, i.e. 3 s:s <= sigma_Y^2
  /// with s the deviator. Its left side is twice the standard one, so its
  /// uniaxial yield stress is sigma_Y/sqrt(2).
  three_d,
  /// Standard 3-D von Mises set (3/2) s:s <= sigma_Y^2.
  three_d_standard
};

/// The model names accepted by parse_model(), comma separated.
inline constexpr const char* model_names = "'1d', 'plane_stress', '3d', '3d_standard'";

/// Parse a model name.
/// @param name One of "1d", "plane_stress", "3d", "3d_standard".
/// @return The model.
/// @throws std::invalid_argument naming `model` if the name is unknown.
inline Model parse_model(const std::string& name)
{
  if (name == "1d")
    return Model::uniaxial;
  if (name == "plane_stress")
    return Model::plane_stress;
  if (name == "3d")
    return Model::three_d;
  if (name == "3d_standard")
    return Model::three_d_standard;
  throw std::invalid_argument("model: unknown model '" + name + "'; valid models are "
                              + model_names);
}

/// Spatial dimension d of the model's stress tensors (1, 2 or 3).
/// @param model The model.
constexpr int dimension(Model model) noexcept
{
  switch (model)
  {
  case Model::uniaxial:
    return 1;
  case Model::plane_stress:
    return 2;
  default:
    return 3;
  }
}

/// Number n = d(d+1)/2 of Mandel components of the model.
/// @param model The model.
constexpr int mandel_size(Model model) noexcept
{
  const int d = dimension(model);
  return d * (d + 1) / 2;
}

/// The orthonormal eigenbasis shared by E and Y, as the rows of an n x n
/// row-major matrix Q: eigen-coordinates are z = Q m for a Mandel vector m,
/// and m = Q^T z. The row order matches elastic_eigenvalues() and
/// yield_eigenvalues().
/// @tparam N Mandel size; must equal mandel_size(model).
/// @param model The model.
template <int N>
std::array<double, N * N> eigenbasis(Model model)
{
  if (mandel_size(model) != N)
    throw std::invalid_argument("model: Mandel size does not match the template size N");
  std::array<double, N * N> Q{};
  if constexpr (N == 1)
  {
    Q[0] = 1.0;
  }
  else if constexpr (N == 3)
  {
    const double r2 = 1.0 / std::sqrt(2.0);
    Q = {r2, r2, 0.0, r2, -r2, 0.0, 0.0, 0.0, 1.0};
  }
  else if constexpr (N == 6)
  {
    const double r3 = 1.0 / std::sqrt(3.0);
    const double r2 = 1.0 / std::sqrt(2.0);
    const double r6 = 1.0 / std::sqrt(6.0);
    Q = {r3,  r3,  r3,        0.0, 0.0, 0.0,  // volumetric
         r2,  -r2, 0.0,       0.0, 0.0, 0.0,  // deviatoric, normal
         r6,  r6,  -2.0 * r6, 0.0, 0.0, 0.0,  // deviatoric, normal
         0.0, 0.0, 0.0,       1.0, 0.0, 0.0,  // shear 23
         0.0, 0.0, 0.0,       0.0, 1.0, 0.0,  // shear 13
         0.0, 0.0, 0.0,       0.0, 0.0, 1.0}; // shear 12
  }
  else
  {
    static_assert(N == 1 || N == 3 || N == 6, "Mandel size must be 1, 3 or 6");
  }
  return Q;
}

} // namespace vpcontact
