// SPDX-License-Identifier: MIT
/// @file mandel.hpp
/// @brief Symmetric tensors as orthonormal Mandel vectors.
///
/// A symmetric d x d tensor t is stored as the n = d(d+1)/2 vector of its
/// coordinates in the orthonormal basis B_a of symmetric tensors,
///
///     1-D: [t11]
///     2-D: [t11, t22, sqrt2 t12]
///     3-D: [t11, t22, t33, sqrt2 t23, sqrt2 t13, sqrt2 t12],
///
/// with B_a = e_i (x) e_i for a diagonal pair (i, i) and
/// B_a = (e_i (x) e_j + e_j (x) e_i)/sqrt2 for an off-diagonal pair. The map is
/// an isometry: s : t equals the dot product of the Mandel vectors, and a
/// symmetric fourth-order operator becomes an n x n matrix C with
/// T_ijkl = sum_ab C_ab (B_a)_ij (B_b)_kl.
#pragma once

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace vpcontact
{

/// Number of Mandel components n = d(d+1)/2 of a symmetric d x d tensor.
/// @param d Spatial dimension.
constexpr int mandel_size_of_dimension(int d) noexcept { return d * (d + 1) / 2; }

namespace detail
{
// Row/column index pair (i, j) of Mandel component a, for d = 1, 2, 3.
inline constexpr int pair_row_3[6] = {0, 1, 2, 1, 0, 0};
inline constexpr int pair_col_3[6] = {0, 1, 2, 2, 2, 1};
inline constexpr int pair_row_2[3] = {0, 1, 0};
inline constexpr int pair_col_2[3] = {0, 1, 1};
inline constexpr int pair_1[1] = {0};

inline void check_dimension(int d)
{
  if (d < 1 || d > 3)
    throw std::invalid_argument("d: dimension must be 1, 2 or 3, got " + std::to_string(d));
}
} // namespace detail

/// Tensor indices (i, j), i <= j, of Mandel component a.
/// @param d Spatial dimension (1, 2 or 3).
/// @param a Mandel component, 0 <= a < d(d+1)/2.
/// @param i Row index (output).
/// @param j Column index (output).
inline void mandel_pair(int d, int a, int& i, int& j) noexcept
{
  const int* rows = d == 3 ? detail::pair_row_3 : (d == 2 ? detail::pair_row_2 : detail::pair_1);
  const int* cols = d == 3 ? detail::pair_col_3 : (d == 2 ? detail::pair_col_2 : detail::pair_1);
  i = rows[a];
  j = cols[a];
}

/// Convert tensors to Mandel vectors. Off-diagonal entries are averaged,
/// (t_ij + t_ji)/2, so the map is the orthogonal projection onto symmetric
/// tensors followed by the isometry.
/// @param d Spatial dimension (1, 2 or 3).
/// @param num_points Number of tensors.
/// @param t Tensors, num_points x d x d, row-major.
/// @param m Mandel vectors (output), num_points x n.
inline void to_mandel(int d, std::size_t num_points, const double* t, double* m)
{
  detail::check_dimension(d);
  const int n = mandel_size_of_dimension(d);
  const double r2 = std::sqrt(0.5);
  for (std::size_t p = 0; p < num_points; ++p)
  {
    const double* tp = t + p * d * d;
    double* mp = m + p * n;
    for (int a = 0; a < n; ++a)
    {
      int i, j;
      mandel_pair(d, a, i, j);
      mp[a] = i == j ? tp[i * d + i] : r2 * (tp[i * d + j] + tp[j * d + i]);
    }
  }
}

/// Convert Mandel vectors to symmetric tensors.
/// @param d Spatial dimension (1, 2 or 3).
/// @param num_points Number of vectors.
/// @param m Mandel vectors, num_points x n.
/// @param t Tensors (output), num_points x d x d, row-major.
inline void from_mandel(int d, std::size_t num_points, const double* m, double* t)
{
  detail::check_dimension(d);
  const int n = mandel_size_of_dimension(d);
  const double r2 = std::sqrt(0.5);
  for (std::size_t p = 0; p < num_points; ++p)
  {
    const double* mp = m + p * n;
    double* tp = t + p * d * d;
    for (int a = 0; a < n; ++a)
    {
      int i, j;
      mandel_pair(d, a, i, j);
      const double v = i == j ? mp[a] : r2 * mp[a];
      tp[i * d + j] = v;
      tp[j * d + i] = v;
    }
  }
}

/// Convert n x n Mandel matrices to fourth-order tensors with both minor
/// symmetries, T_ijkl = sum_ab C_ab (B_a)_ij (B_b)_kl, so that
/// T : de equals the tensor of C m(de) for every symmetric de.
/// @param d Spatial dimension (1, 2 or 3).
/// @param num_points Number of matrices.
/// @param C Mandel matrices, num_points x n x n, row-major.
/// @param T Tensors (output), num_points x d x d x d x d, row-major.
inline void matrix_from_mandel(int d, std::size_t num_points, const double* C, double* T)
{
  detail::check_dimension(d);
  const int n = mandel_size_of_dimension(d);
  const int d2 = d * d;
  const double r2 = std::sqrt(0.5);
  for (std::size_t p = 0; p < num_points; ++p)
  {
    const double* Cp = C + p * n * n;
    double* Tp = T + p * d2 * d2;
    for (int a = 0; a < n; ++a)
    {
      int i, j;
      mandel_pair(d, a, i, j);
      const double ba = i == j ? 1.0 : r2;
      for (int b = 0; b < n; ++b)
      {
        int k, l;
        mandel_pair(d, b, k, l);
        const double v = ba * (k == l ? 1.0 : r2) * Cp[a * n + b];
        Tp[(i * d + j) * d2 + k * d + l] = v;
        Tp[(j * d + i) * d2 + k * d + l] = v;
        Tp[(i * d + j) * d2 + l * d + k] = v;
        Tp[(j * d + i) * d2 + l * d + k] = v;
      }
    }
  }
}

} // namespace vpcontact
