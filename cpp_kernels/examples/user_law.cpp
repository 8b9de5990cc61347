// SPDX-License-Identifier: MIT
// Using the kernels from C++ alone (no Python), with a user-defined law.
//
// A new viscoplastic law only has to model the ViscoplasticLaw concept of
// viscoplastic_law.hpp; the implicit step then solves its local equation by
// Newton's method with the law's derivatives. Here: a nonlinear relaxation law
//     G(sigma, eps) = -(1/eta) |sigma|^2 sigma + b eps
// in plane stress. The program checks the step against its defining equation
// and the tangent against central finite differences, and exits non-zero on
// failure. Build: g++ -std=c++17 -I cpp_kernels/include user_law.cpp
#include <vpcontact/kernels.hpp>

#include <array>
#include <cmath>
#include <cstdio>

namespace
{
struct CubicRelaxation
{
  static constexpr int size = 3;
  double eta;
  double b;

  void G(const double* sigma, const double* eps, double* g) const noexcept
  {
    const double s2 = sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2];
    for (int i = 0; i < size; ++i)
      g[i] = -s2 * sigma[i] / eta + b * eps[i];
  }

  void dG_dsigma(const double* sigma, const double*, double* J) const noexcept
  {
    const double s2 = sigma[0] * sigma[0] + sigma[1] * sigma[1] + sigma[2] * sigma[2];
    for (int i = 0; i < size; ++i)
      for (int j = 0; j < size; ++j)
        J[i * size + j] = -((i == j ? s2 : 0.0) + 2.0 * sigma[i] * sigma[j]) / eta;
  }

  void dG_deps(const double*, const double*, double* J) const noexcept
  {
    for (int i = 0; i < size * size; ++i)
      J[i] = i % (size + 1) == 0 ? b : 0.0;
  }
};
static_assert(vpcontact::is_viscoplastic_law_v<CubicRelaxation>);
} // namespace

int main()
{
  using namespace vpcontact;
  const Elasticity elasticity{Model::plane_stress, 200.0, 0.25};
  const CubicRelaxation law{0.5, 3.0};
  const double dt = 0.1;
  std::array<double, 3> sigma_old{1.0, -0.5, 0.3}, eps_old{0.01, 0.0, -0.02},
      eps_new{0.03, -0.01, 0.01}, sigma_new{}, plus{}, minus{};
  std::array<double, 9> tangent{};
  implicit_update(
      law, elasticity, dt,
      {1, sigma_old.data(), eps_old.data(), eps_new.data(), sigma_new.data(), tangent.data()});

  // sigma_n = sigma_{n-1} + E (eps_n - eps_{n-1}) + dt G(sigma_n, eps_n).
  const std::array<double, 9> C = elasticity_matrix<3>(elasticity);
  std::array<double, 3> g{};
  law.G(sigma_new.data(), eps_new.data(), g.data());
  double residual = 0.0;
  for (int i = 0; i < 3; ++i)
  {
    double r = sigma_new[i] - sigma_old[i] - dt * g[i];
    for (int j = 0; j < 3; ++j)
      r -= C[i * 3 + j] * (eps_new[j] - eps_old[j]);
    residual = std::fmax(residual, std::fabs(r));
  }
  if (!(residual < 1e-12))
  {
    std::printf("residual %g\n", residual);
    return 1;
  }

  // Tangent against central differences.
  const double h = 1e-6;
  double worst = 0.0;
  for (int j = 0; j < 3; ++j)
  {
    std::array<double, 3> ep = eps_new, em = eps_new;
    ep[j] += h;
    em[j] -= h;
    implicit_update(law, elasticity, dt,
                    {1, sigma_old.data(), eps_old.data(), ep.data(), plus.data(), nullptr});
    implicit_update(law, elasticity, dt,
                    {1, sigma_old.data(), eps_old.data(), em.data(), minus.data(), nullptr});
    for (int i = 0; i < 3; ++i)
      worst = std::fmax(worst, std::fabs((plus[i] - minus[i]) / (2 * h) - tangent[i * 3 + j]));
  }
  if (!(worst < 1e-6 * 200.0))
  {
    std::printf("tangent error %g\n", worst);
    return 1;
  }
  std::printf("ok: residual %.2e, tangent error %.2e\n", residual, worst);
  return 0;
}
