// One V-cycle of hypre's BoomerAMG as a preconditioner (private to fluid_mps; the public headers
// include no hypre or MPI header).
#pragma once

#include <memory>
#include <vector>

#include "cosim/fluid_mps/pressure_solver.hpp"

namespace cosim::mps {

class AmgPreconditioner {
 public:
  AmgPreconditioner();
  ~AmgPreconditioner();
  AmgPreconditioner(const AmgPreconditioner&) = delete;
  AmgPreconditioner& operator=(const AmgPreconditioner&) = delete;

  // Builds the hierarchy of `matrix` (symmetric positive definite, diagonal stored in each row).
  void setup(const SparseRows& matrix);
  // z = M^-1 r: one V-cycle from z = 0.
  void apply(const std::vector<double>& r, std::vector<double>& z);

 private:
  struct Hypre;
  std::unique_ptr<Hypre> hypre_;
};

}  // namespace cosim::mps
