// SPDX-License-Identifier: MIT
/// @file small_matrix.hpp
/// @brief Fixed-size dense linear algebra for n x n Mandel matrices (n <= 6):
/// products and an LU solve with partial pivoting. Row-major storage, no
/// allocation.
#pragma once

#include <array>
#include <cmath>
#include <utility>

namespace vpcontact::detail
{

template <int N>
using Vector = std::array<double, N>;

template <int N>
using Matrix = std::array<double, N * N>;

/// y = A x.
template <int N>
inline Vector<N> multiply(const Matrix<N>& A, const Vector<N>& x) noexcept
{
  Vector<N> y{};
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j)
      y[i] += A[i * N + j] * x[j];
  return y;
}

/// y = A^T x.
template <int N>
inline Vector<N> multiply_transposed(const Matrix<N>& A, const Vector<N>& x) noexcept
{
  Vector<N> y{};
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j)
      y[j] += A[i * N + j] * x[i];
  return y;
}

/// Euclidean norm, scaled against overflow.
template <int N>
inline double norm(const Vector<N>& x) noexcept
{
  double scale = 0.0;
  for (double v : x)
    scale = std::fmax(scale, std::fabs(v));
  if (!(scale > 0.0) || !std::isfinite(scale))
    return scale;
  double sum = 0.0;
  for (double v : x)
    sum += (v / scale) * (v / scale);
  return scale * std::sqrt(sum);
}

/// Load N doubles starting at p.
template <int N>
inline Vector<N> load(const double* p) noexcept
{
  Vector<N> x;
  for (int i = 0; i < N; ++i)
    x[i] = p[i];
  return x;
}

/// Store an array of M doubles at p.
template <std::size_t M>
inline void store(const std::array<double, M>& x, double* p) noexcept
{
  for (std::size_t i = 0; i < M; ++i)
    p[i] = x[i];
}

/// In-place LU factorisation with partial pivoting, PA = LU.
/// @param A Matrix, overwritten by L (unit diagonal, below) and U.
/// @param perm Row permutation (output).
/// @return false if a pivot is exactly zero or not finite (A singular).
template <int N>
inline bool lu_factor(Matrix<N>& A, std::array<int, N>& perm) noexcept
{
  for (int i = 0; i < N; ++i)
    perm[i] = i;
  for (int k = 0; k < N; ++k)
  {
    int p = k;
    for (int i = k + 1; i < N; ++i)
      if (std::fabs(A[i * N + k]) > std::fabs(A[p * N + k]))
        p = i;
    if (!(A[p * N + k] != 0.0) || !std::isfinite(A[p * N + k]))
      return false;
    if (p != k)
    {
      std::swap(perm[p], perm[k]);
      for (int j = 0; j < N; ++j)
        std::swap(A[p * N + j], A[k * N + j]);
    }
    for (int i = k + 1; i < N; ++i)
    {
      const double l = A[i * N + k] / A[k * N + k];
      A[i * N + k] = l;
      for (int j = k + 1; j < N; ++j)
        A[i * N + j] -= l * A[k * N + j];
    }
  }
  return true;
}

/// Solve A x = b with the factors from lu_factor().
template <int N>
inline Vector<N> lu_solve(const Matrix<N>& LU, const std::array<int, N>& perm,
                          const Vector<N>& b) noexcept
{
  Vector<N> x;
  for (int i = 0; i < N; ++i)
  {
    double v = b[perm[i]];
    for (int j = 0; j < i; ++j)
      v -= LU[i * N + j] * x[j];
    x[i] = v;
  }
  for (int i = N - 1; i >= 0; --i)
  {
    double v = x[i];
    for (int j = i + 1; j < N; ++j)
      v -= LU[i * N + j] * x[j];
    x[i] = v / LU[i * N + i];
  }
  return x;
}

/// X = A^{-1} B for an n x n right-hand side, with the factors of A.
template <int N>
inline Matrix<N> lu_solve_matrix(const Matrix<N>& LU, const std::array<int, N>& perm,
                                 const Matrix<N>& B) noexcept
{
  Matrix<N> X;
  for (int c = 0; c < N; ++c)
  {
    Vector<N> b;
    for (int i = 0; i < N; ++i)
      b[i] = B[i * N + c];
    const Vector<N> x = lu_solve<N>(LU, perm, b);
    for (int i = 0; i < N; ++i)
      X[i * N + c] = x[i];
  }
  return X;
}

} // namespace vpcontact::detail
