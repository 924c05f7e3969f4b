// The CG's products over the full rows of the pressure matrix (pressure_solver.cpp): the matrix
// laid out as the products read it, made once a solve, and y = A x over a range of rows. Every
// layout sums each row in the order of its entries, as the plain loop
// `for k: sum += value[k] * x[column[k]]` does, so y has the bits of that loop.
#pragma once

#include <cstdint>

#include "cosim/fluid_mps/pressure_solver.hpp"

namespace cosim::mps {

// Rows summed side by side. A single row's sum is a chain of dependent additions (about 4
// cycles each, about 50 a row in 2D at 4 l0); interleaving independent rows lets the additions
// of a group overlap. Shares of a product start at multiples of it.
constexpr int kRowGroup = 4;

// How a product reads the matrix: the rows interleaved by groups of kRowGroup, slot t of row
// kRowGroup g + r at group_start[g] + kRowGroup t + r, each group as wide as its longest row
// (the shorter rows padded with zeros), so one load reads the values of two rows (SSE2), with
// - double values (row_view without `single`), or
// - float values (`single`, set_single_precision_product): 6 bytes an entry instead of 10 with
//   16-bit columns, so that a thread's share of a 2D matrix of 17 k unknowns at 4 l0 (about
//   8 MB in double) fits a 4 MB L2 cache: honami_field's solve 0.91 as long, with its true
//   residuals in double (docs/performance.md). Each value converts exactly to double, so the
//   products have the bits of the plain loop over double(float(value)).
// Column indices in 16 bits up to 65 536 rows. Without groups (exact_view of a float view) the
// product reads the double values in the rows' own layout.
struct RowView {
  const SparseRows* m = nullptr;
  const std::int64_t* group_start = nullptr;          // null: the rows' own layout, double values
  const double* group_value = nullptr;                // the groups' values: double, or
  const float* group_single_value = nullptr;          // float
  const std::uint16_t* group_short_column = nullptr;  // null: group_column
  const int* group_column = nullptr;
};

// The view of `m` the CG iterations read, its storage in `work`.
RowView row_view(const SparseRows& m, CgWork& work, bool single);

// The same matrix with its double values (the true residuals): `view` itself unless it reads
// float values, then the rows' own layout.
RowView exact_view(const RowView& view);

// Rows [begin, end) of y = A x; `begin` a multiple of kRowGroup.
void multiply_rows(const RowView& view, const double* x, int begin, int end, double* y);

}  // namespace cosim::mps
