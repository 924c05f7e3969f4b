#include "cosim/fluid_mps/restart.hpp"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace cosim::mps {
namespace {

constexpr char kMagic[8] = {'C', 'O', 'S', 'I', 'M', 'M', 'P', 'S'};
constexpr std::uint32_t kVersion = 1;

template <class T>
void write(std::ofstream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <class T>
void read(std::ifstream& in, T& value, const std::string& path) {
  in.read(reinterpret_cast<char*>(&value), sizeof(T));
  if (!in) throw std::runtime_error("load_state: truncated file " + path);
}

}  // namespace

void save_state(const FluidSystem& system, const std::string& path) {
  save_state(system.save_state(), path);
}

void save_state(const MpsState& state, const std::string& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("save_state: cannot open " + path);
  out.write(kMagic, sizeof(kMagic));
  write(out, kVersion);
  const std::uint64_t n = state.positions.size();
  write(out, n);
  write(out, state.time);
  write(out, static_cast<std::int64_t>(state.step));
  for (std::uint64_t i = 0; i < n; ++i) {
    for (int axis = 0; axis < 3; ++axis) write(out, state.positions[i][axis]);
    for (int axis = 0; axis < 3; ++axis) write(out, state.velocities[i][axis]);
    write(out, state.pressures[i]);
    write(out, static_cast<std::int32_t>(state.kinds[i]));
  }
  if (!out) throw std::runtime_error("save_state: write failed for " + path);
}

MpsState load_state(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("load_state: cannot open " + path);
  char magic[8];
  in.read(magic, sizeof(magic));
  std::uint32_t version = 0;
  read(in, version, path);
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0 || version != kVersion) {
    throw std::runtime_error("load_state: " + path + " is not a fluid_mps restart file (v1)");
  }
  std::uint64_t n = 0;
  std::int64_t step = 0;
  MpsState state;
  read(in, n, path);
  read(in, state.time, path);
  read(in, step, path);
  state.step = step;
  state.positions.resize(n);
  state.velocities.resize(n);
  state.pressures.resize(n);
  state.kinds.resize(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    for (int axis = 0; axis < 3; ++axis) read(in, state.positions[i][axis], path);
    for (int axis = 0; axis < 3; ++axis) read(in, state.velocities[i][axis], path);
    read(in, state.pressures[i], path);
    std::int32_t kind = 0;
    read(in, kind, path);
    if (kind < 0 || kind > 3) throw std::runtime_error("load_state: bad particle kind in " + path);
    state.kinds[i] = static_cast<ParticleKind>(kind);
  }
  return state;
}

}  // namespace cosim::mps
