// SPDX-License-Identifier: MIT
/// @file kernels.hpp
/// @brief Array entry points with the model and scheme chosen at run time
/// (the functions bound to Python). Includes all other headers.
#pragma once

#include "elasticity.hpp"
#include "mandel.hpp"
#include "model.hpp"
#include "stress_update.hpp"
#include "viscoplastic_law.hpp"
#include "yield_sets.hpp"

#include <array>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace vpcontact
{

/// Time-stepping schemes for the viscoplastic term.
enum class Scheme
{
  /// G evaluated at (sigma_{n-1}, eps_{n-1}).
  explicit_euler,
  /// G evaluated at (sigma_n, eps_n).
  implicit_euler,
  /// G linearised at (sigma_{n-1}, eps_{n-1}) and taken at (sigma_n, eps_n).
  linearized_euler
};

/// Parse a scheme name.
/// @param name "explicit", "implicit" or "linearized".
/// @throws std::invalid_argument naming `scheme` if the name is unknown.
inline Scheme parse_scheme(const std::string& name)
{
  if (name == "explicit")
    return Scheme::explicit_euler;
  if (name == "implicit")
    return Scheme::implicit_euler;
  if (name == "linearized")
    return Scheme::linearized_euler;
  throw std::invalid_argument("scheme: unknown scheme '" + name
                              + "'; valid schemes are 'explicit', 'implicit', 'linearized'");
}

/// Call f(std::integral_constant<int, n>{}) with n = mandel_size(model).
/// @param model The model.
/// @param f A generic callable.
template <class F>
decltype(auto) dispatch(Model model, F&& f)
{
  switch (mandel_size(model))
  {
  case 1:
    return f(std::integral_constant<int, 1>{});
  case 3:
    return f(std::integral_constant<int, 3>{});
  default:
    return f(std::integral_constant<int, 6>{});
  }
}

/// Project num_points Mandel stresses onto K in the energy norm.
/// @param elasticity Elastic constants (with the model).
/// @param sigma_y Yield stress, > 0 (+infinity: no projection).
/// @param num_points Number of points.
/// @param sigma Input, num_points x n.
/// @param tau Output, num_points x n (may alias sigma).
inline void project(const Elasticity& elasticity, double sigma_y, std::size_t num_points,
                    const double* sigma, double* tau)
{
  dispatch(elasticity.model,
           [&](auto n)
           {
             constexpr int N = decltype(n)::value;
             project<N>(YieldSet<N>(elasticity, sigma_y), num_points, sigma, tau);
           });
}

/// Perzyna step (explicit: generic; implicit: exact specialisation;
/// linearized: elastic at points in K, generic elsewhere).
/// @param scheme Time-stepping scheme.
/// @param elasticity Elastic constants (with the model).
/// @param sigma_y Yield stress, > 0.
/// @param mu_star Viscosity mu* > 0.
/// @param dt Time step > 0.
/// @param step The arrays.
inline void perzyna_update(Scheme scheme, const Elasticity& elasticity, double sigma_y,
                           double mu_star, double dt, const StepArrays& step)
{
  dispatch(elasticity.model,
           [&](auto n)
           {
             constexpr int N = decltype(n)::value;
             const Perzyna<N> law(YieldSet<N>(elasticity, sigma_y), mu_star);
             if (scheme == Scheme::explicit_euler)
               explicit_update(law, elasticity, dt, step);
             else if (scheme == Scheme::linearized_euler)
               linearized_update(law, elasticity, dt, step);
             else
               implicit_update(law, elasticity, dt, step);
           });
}

/// Implicit Perzyna step by the generic Newton iteration (for testing the
/// ViscoplasticLaw machinery against the exact specialisation).
inline void perzyna_update_newton(const Elasticity& elasticity, double sigma_y, double mu_star,
                                  double dt, const StepArrays& step)
{
  dispatch(elasticity.model,
           [&](auto n)
           {
             constexpr int N = decltype(n)::value;
             const Perzyna<N> law(YieldSet<N>(elasticity, sigma_y), mu_star);
             implicit_update_newton(law, elasticity, dt, step);
           });
}

/// Step with G = a sigma + b eps (implicit: closed form; linearized: generic,
/// equal to the implicit step up to round-off).
/// @param scheme Time-stepping scheme.
/// @param elasticity Elastic constants (with the model).
/// @param a Coefficient of sigma.
/// @param b Coefficient of eps.
/// @param dt Time step > 0.
/// @param step The arrays.
inline void linear_update(Scheme scheme, const Elasticity& elasticity, double a, double b,
                          double dt, const StepArrays& step)
{
  dispatch(elasticity.model,
           [&](auto n)
           {
             constexpr int N = decltype(n)::value;
             const LinearG<N> law(a, b);
             if (scheme == Scheme::explicit_euler)
               explicit_update(law, elasticity, dt, step);
             else if (scheme == Scheme::linearized_euler)
               linearized_update(law, elasticity, dt, step);
             else
               implicit_update(law, elasticity, dt, step);
           });
}

/// Implicit step with G = a sigma + b eps by the generic Newton iteration.
inline void linear_update_newton(const Elasticity& elasticity, double a, double b, double dt,
                                 const StepArrays& step)
{
  dispatch(elasticity.model,
           [&](auto n)
           {
             constexpr int N = decltype(n)::value;
             implicit_update_newton(LinearG<N>(a, b), elasticity, dt, step);
           });
}

/// Write the n x n Mandel matrix of E.
/// @param elasticity Elastic constants (with the model).
/// @param C Output, n x n.
inline void elasticity_matrix(const Elasticity& elasticity, double* C)
{
  dispatch(elasticity.model,
           [&](auto n)
           {
             constexpr int N = decltype(n)::value;
             detail::store(elasticity_matrix<N>(elasticity), C);
           });
}

/// Write the n x n Mandel matrix of Y.
/// @param model The model.
/// @param Y Output, n x n.
inline void yield_matrix(Model model, double* Y)
{
  dispatch(model,
           [&](auto n)
           {
             constexpr int N = decltype(n)::value;
             detail::store(yield_matrix<N>(model), Y);
           });
}

/// Evaluate tau . Y tau at num_points Mandel stresses.
/// @param model The model.
/// @param num_points Number of points.
/// @param tau Input, num_points x n.
/// @param values Output, num_points.
inline void yield_function(Model model, std::size_t num_points, const double* tau, double* values)
{
  dispatch(model,
           [&](auto n)
           {
             constexpr int N = decltype(n)::value;
             yield_function<N>(model, num_points, tau, values);
           });
}

} // namespace vpcontact
