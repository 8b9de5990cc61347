// SPDX-License-Identifier: MIT
/// @file patch_smoother.hpp
/// @brief Additive Schwarz smoothing on small patches of a sparse matrix (the vertex stars of a
/// P2 displacement block): each patch's block is factorized densely once per matrix, and a
/// sweep solves every patch exactly for the same residual and adds the damped corrections.
/// Rows are the caller's local rows; a patch holds local row indices only (couplings to other
/// processes' unknowns are left out of the blocks).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace vpcontact
{

/// A compressed-row view of the local rows of a sparse matrix: row i's entries are
/// columns[row_start[i] .. row_start[i+1]) with their values. Columns are global: column j
/// is local row j - first_column, and one outside [0, num_rows) after that shift (another
/// process's unknown) is skipped.
struct LocalCsr
{
  std::size_t num_rows = 0;
  const std::int64_t* row_start = nullptr;
  const std::int64_t* columns = nullptr;
  const double* values = nullptr;
  std::int64_t first_column = 0;
};

/// Exact solves on overlapping patches of unknowns.
class PatchSmoother
{
public:
  /// @param offsets patch p holds indices[offsets[p] .. offsets[p+1]); size: patches + 1.
  /// @param indices local row indices, each in [0, num_rows), no repeats within a patch.
  /// @param num_rows number of local rows of the matrices this smoother will factorize.
  /// @throws std::invalid_argument naming `offsets` or `indices` when they do not describe
  /// patches of [0, num_rows).
  PatchSmoother(std::vector<std::int64_t> offsets, std::vector<std::int64_t> indices,
                std::size_t num_rows)
      : offsets_(std::move(offsets)), indices_(std::move(indices)), num_rows_(num_rows)
  {
    if (offsets_.empty() || offsets_.front() != 0
        || offsets_.back() != static_cast<std::int64_t>(indices_.size())
        || !std::is_sorted(offsets_.begin(), offsets_.end()))
      throw std::invalid_argument("offsets: must rise from 0 to the number of indices");
    std::vector<std::int64_t> seen(num_rows_, -1);
    std::size_t factor_size = 0;
    for (std::size_t p = 0; p + 1 < offsets_.size(); ++p)
    {
      for (std::int64_t k = offsets_[p]; k < offsets_[p + 1]; ++k)
      {
        const std::int64_t i = indices_[k];
        if (i < 0 || i >= static_cast<std::int64_t>(num_rows_))
          throw std::invalid_argument("indices: " + std::to_string(i) + " is not a local row");
        if (seen[i] == static_cast<std::int64_t>(p))
          throw std::invalid_argument("indices: row " + std::to_string(i)
                                      + " repeated in patch " + std::to_string(p));
        seen[i] = static_cast<std::int64_t>(p);
      }
      factor_start_.push_back(factor_size);
      const std::size_t n = static_cast<std::size_t>(offsets_[p + 1] - offsets_[p]);
      factor_size += n * n;
      max_patch_ = std::max(max_patch_, n);
    }
    factor_start_.push_back(factor_size);
    factors_.assign(factor_size, 0.0);
    pivots_.assign(indices_.size(), 0);
    position_.assign(num_rows_, -1);
  }

  /// Number of patches.
  std::size_t size() const noexcept { return offsets_.size() - 1; }

  /// Number of local rows of the matrices and vectors this smoother works on.
  std::size_t num_rows() const noexcept { return num_rows_; }

  /// Number of patches whose block was singular at the last factorization (they are
  /// smoothed by their diagonal instead).
  std::size_t singular() const noexcept { return singular_; }

  /// Factorize every patch's block of `A` (LU with partial pivoting, in place), or only the
  /// listed patches' (the others keep their factors: `A` differs from the last matrix only in
  /// rows and columns of no other patch).
  /// @param A the local rows; A.num_rows must be this smoother's.
  /// @param patches the patches to refactorize, or nullptr for all of them.
  /// @param count the number of listed patches.
  /// @throws std::invalid_argument naming `A` if its row count differs, `patches` if one is out
  /// of range or nothing was factorized before.
  void factorize(const LocalCsr& A, const std::int64_t* patches = nullptr, std::size_t count = 0)
  {
    if (A.num_rows != num_rows_)
      throw std::invalid_argument("A: " + std::to_string(A.num_rows) + " rows, the patches have "
                                  + std::to_string(num_rows_));
    if (patches == nullptr)
      diagonal_only_.assign(size(), false);
    else
    {
      if (!factorized_)
        throw std::invalid_argument("patches: factorize all of them first");
      check_patches(patches, count);
    }
    const std::size_t todo = patches == nullptr ? size() : count;
    for (std::size_t q = 0; q < todo; ++q)
    {
      const std::size_t p = patches == nullptr ? q : static_cast<std::size_t>(patches[q]);
      diagonal_only_[p] = false;
      const std::int64_t* rows = indices_.data() + offsets_[p];
      const std::size_t n = static_cast<std::size_t>(offsets_[p + 1] - offsets_[p]);
      double* F = factors_.data() + factor_start_[p];
      std::fill(F, F + n * n, 0.0);
      for (std::size_t a = 0; a < n; ++a)
        position_[rows[a]] = static_cast<std::int64_t>(a);
      for (std::size_t a = 0; a < n; ++a)
        for (std::int64_t k = A.row_start[rows[a]]; k < A.row_start[rows[a] + 1]; ++k)
        {
          const std::int64_t j = A.columns[k] - A.first_column;
          if (j >= 0 && j < static_cast<std::int64_t>(num_rows_) && position_[j] >= 0)
            F[a * n + static_cast<std::size_t>(position_[j])] = A.values[k];
        }
      for (std::size_t a = 0; a < n; ++a)
        position_[rows[a]] = -1;
      if (lu(F, pivots_.data() + offsets_[p], n))
        transpose(F, n); // column-major factors: substitutions by contiguous columns
      else
      {
        diagonal_only_[p] = true;
        for (std::size_t a = 0; a < n; ++a) // the diagonal again, for the fallback
        {
          F[a * n + a] = 0.0;
          for (std::int64_t k = A.row_start[rows[a]]; k < A.row_start[rows[a] + 1]; ++k)
            if (A.columns[k] - A.first_column == rows[a])
              F[a * n + a] = A.values[k];
        }
      }
    }
    singular_ = static_cast<std::size_t>(
        std::count(diagonal_only_.begin(), diagonal_only_.end(), true));
    factorized_ = true;
  }

  /// One sweep from zero: y = omega * sum_p R_p^T A_pp^{-1} R_p r.
  /// @param r residual (num_rows values); @param y output (num_rows values).
  void apply(const double* r, double* y, double omega) const
  {
    check_factorized();
    std::fill(y, y + num_rows_, 0.0);
    std::vector<double> work(max_patch_);
    for (std::size_t p = 0; p < size(); ++p)
    {
      const std::int64_t* rows = indices_.data() + offsets_[p];
      const std::size_t n = static_cast<std::size_t>(offsets_[p + 1] - offsets_[p]);
      for (std::size_t a = 0; a < n; ++a)
        work[a] = r[rows[a]];
      solve(p, work.data());
      for (std::size_t a = 0; a < n; ++a)
        y[rows[a]] += omega * work[a];
    }
  }

  /// The patches' Schur complements summed: S = sum_p B_p A_pp^{-1} B_p^T, with B_p^T the rows
  /// of `Bt` on patch p (every column kept: Bt couples these rows to another field, e.g. the
  /// pressure, whose global indices its columns are). Returned as coordinates: each patch adds
  /// the m x m entries of the columns its rows touch (stored zeros included, so the pattern
  /// depends only on Bt's pattern), in patch order; `starts` (patches + 1 values) gives where
  /// each patch's entries begin. With `patches`, only the listed patches' entries, in the
  /// listed order (and `starts` over them).
  /// @param Bt the local rows of the coupling block; Bt.num_rows must be this smoother's.
  /// @throws std::invalid_argument naming `Bt` if its row count differs, `patches` if one is
  /// out of range.
  void schur_sum(const LocalCsr& Bt, std::vector<std::int64_t>& rows,
                 std::vector<std::int64_t>& cols, std::vector<double>& values,
                 std::vector<std::int64_t>& starts, const std::int64_t* patches = nullptr,
                 std::size_t count = 0) const
  {
    check_factorized();
    if (Bt.num_rows != num_rows_)
      throw std::invalid_argument("Bt: " + std::to_string(Bt.num_rows)
                                  + " rows, the patches have " + std::to_string(num_rows_));
    if (patches != nullptr)
      check_patches(patches, count);
    rows.clear();
    cols.clear();
    values.clear();
    starts.assign(1, 0);
    SchurWork work;
    const std::size_t todo = patches == nullptr ? size() : count;
    for (std::size_t q = 0; q < todo; ++q)
    {
      patch_schur(patches == nullptr ? q : static_cast<std::size_t>(patches[q]), Bt, work, rows,
                  cols, values);
      starts.push_back(static_cast<std::int64_t>(values.size()));
    }
  }

private:
  std::vector<std::int64_t> offsets_, indices_;
  std::size_t num_rows_;
  std::vector<std::size_t> factor_start_;
  std::vector<double> factors_;
  std::vector<std::int64_t> pivots_;
  std::vector<std::int64_t> position_;
  std::vector<bool> diagonal_only_;
  std::size_t max_patch_ = 0; // rows of the largest patch
  std::size_t singular_ = 0;
  bool factorized_ = false;

  /// Scratch space of patch_schur.
  struct SchurWork
  {
    std::vector<std::int64_t> touched;
    std::vector<double> dense, solved, by_row, block;
  };

  /// Patch p's m x m entries of B_p A_pp^{-1} B_p^T appended (see schur_sum).
  void patch_schur(std::size_t p, const LocalCsr& Bt, SchurWork& w,
                   std::vector<std::int64_t>& rows, std::vector<std::int64_t>& cols,
                   std::vector<double>& values) const
  {
    const std::int64_t* patch = indices_.data() + offsets_[p];
    const std::size_t n = static_cast<std::size_t>(offsets_[p + 1] - offsets_[p]);
    std::vector<std::int64_t>& touched = w.touched;
    touched.clear();
    for (std::size_t a = 0; a < n; ++a)
      touched.insert(touched.end(), Bt.columns + Bt.row_start[patch[a]],
                     Bt.columns + Bt.row_start[patch[a] + 1]);
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    const std::size_t m = touched.size();
    if (m == 0)
      return;
    w.dense.assign(m * n, 0.0); // column c of B_p^T, contiguous: dense[c * n + a]
    for (std::size_t a = 0; a < n; ++a)
      for (std::int64_t k = Bt.row_start[patch[a]]; k < Bt.row_start[patch[a] + 1]; ++k)
      {
        const auto c = static_cast<std::size_t>(
            std::lower_bound(touched.begin(), touched.end(), Bt.columns[k]) - touched.begin());
        w.dense[c * n + a] += Bt.values[k];
      }
    w.solved = w.dense;
    for (std::size_t c = 0; c < m; ++c)
      solve(p, w.solved.data() + c * n);
    // entry (c, d) = column c of B_p^T . A_pp^{-1} column d: accumulated over the star's rows
    // a with the m entries of row a of the solved columns side by side (independent
    // multiply-adds over contiguous memory, not m^2 dot products of dependent additions)
    w.by_row.resize(n * m);
    for (std::size_t d = 0; d < m; ++d)
      for (std::size_t a = 0; a < n; ++a)
        w.by_row[a * m + d] = w.solved[d * n + a];
    w.block.assign(m * m, 0.0);
    for (std::size_t c = 0; c < m; ++c)
    {
      double* __restrict out = w.block.data() + c * m;
      for (std::size_t a = 0; a < n; ++a)
      {
        const double b = w.dense[c * n + a];
        if (b == 0.0)
          continue;
        const double* __restrict in = w.by_row.data() + a * m;
        for (std::size_t d = 0; d < m; ++d)
          out[d] += b * in[d];
      }
    }
    for (std::size_t c = 0; c < m; ++c)
      for (std::size_t d = 0; d < m; ++d)
      {
        rows.push_back(touched[c]);
        cols.push_back(touched[d]);
        values.push_back(w.block[c * m + d]);
      }
  }

  void check_patches(const std::int64_t* patches, std::size_t count) const
  {
    for (std::size_t q = 0; q < count; ++q)
      if (patches[q] < 0 || patches[q] >= static_cast<std::int64_t>(size()))
        throw std::invalid_argument("patches: " + std::to_string(patches[q])
                                    + " is not a patch");
  }

  void check_factorized() const
  {
    if (!factorized_)
      throw std::invalid_argument("PatchSmoother: factorize a matrix before applying it");
  }

  /// LU with partial pivoting of the n x n row-major F in place; false if a pivot is zero
  /// (relative to the block's largest entry) or not finite.
  static bool lu(double* F, std::int64_t* pivot, std::size_t n)
  {
    double scale = 0.0;
    for (std::size_t k = 0; k < n * n; ++k)
      scale = std::fmax(scale, std::fabs(F[k]));
    if (!(scale > 0.0) || !std::isfinite(scale))
      return false;
    for (std::size_t c = 0; c < n; ++c)
    {
      std::size_t best = c;
      for (std::size_t r = c + 1; r < n; ++r)
        if (std::fabs(F[r * n + c]) > std::fabs(F[best * n + c]))
          best = r;
      pivot[c] = static_cast<std::int64_t>(best);
      if (!(std::fabs(F[best * n + c]) > 1e-14 * scale))
        return false;
      if (best != c)
        for (std::size_t k = 0; k < n; ++k)
          std::swap(F[c * n + k], F[best * n + k]);
      const double inv = 1.0 / F[c * n + c];
      for (std::size_t r = c + 1; r < n; ++r)
      {
        const double m = F[r * n + c] * inv;
        F[r * n + c] = m;
        if (m != 0.0)
          for (std::size_t k = c + 1; k < n; ++k)
            F[r * n + k] -= m * F[c * n + k];
      }
    }
    return true;
  }

  /// The n x n row-major F transposed in place.
  static void transpose(double* F, std::size_t n)
  {
    for (std::size_t r = 0; r < n; ++r)
      for (std::size_t c = r + 1; c < n; ++c)
        std::swap(F[r * n + c], F[c * n + r]);
  }

  /// x <- A_pp^{-1} x with patch p's factors (or its diagonal where the block was singular).
  /// The factors are stored by columns (T = F^T), so both substitutions subtract whole
  /// columns: independent multiply-adds over contiguous memory, which the compiler vectorizes
  /// (row-wise dot products are a chain of dependent additions: 2-3x slower on 45 x 45 stars).
  void solve(std::size_t p, double* __restrict x) const
  {
    const std::size_t n = static_cast<std::size_t>(offsets_[p + 1] - offsets_[p]);
    const double* __restrict T = factors_.data() + factor_start_[p];
    if (diagonal_only_[p])
    {
      for (std::size_t a = 0; a < n; ++a)
        x[a] = T[a * n + a] != 0.0 ? x[a] / T[a * n + a] : 0.0;
      return;
    }
    const std::int64_t* pivot = pivots_.data() + offsets_[p];
    for (std::size_t c = 0; c < n; ++c)
      std::swap(x[c], x[static_cast<std::size_t>(pivot[c])]);
    for (std::size_t c = 0; c + 1 < n; ++c) // L (unit diagonal): column c below the diagonal
    {
      const double xc = x[c];
      const double* __restrict column = T + c * n;
      for (std::size_t r = c + 1; r < n; ++r)
        x[r] -= column[r] * xc;
    }
    for (std::size_t r = n; r-- > 0;) // U: column r above the diagonal
    {
      const double* __restrict column = T + r * n;
      x[r] /= column[r];
      const double xr = x[r];
      for (std::size_t k = 0; k < r; ++k)
        x[k] -= column[k] * xr;
    }
  }
};

} // namespace vpcontact
