#include "cosim/fluid_mps/restart.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace cosim::mps {
namespace {

constexpr char kMagic[8] = {'C', 'O', 'S', 'I', 'M', 'M', 'P', 'S'};
constexpr std::uint32_t kVersion = 2;  // 2: the pressure set-up in reuse after the particles

template <class T>
void write(std::ofstream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <class T>
void read(std::ifstream& in, T& value, const std::string& path) {
  in.read(reinterpret_cast<char*>(&value), sizeof(T));
  if (!in) throw std::runtime_error("load_state: truncated file " + path);
}

template <class T>
void write_array(std::ofstream& out, const std::vector<T>& values) {
  write(out, static_cast<std::uint64_t>(values.size()));
  out.write(reinterpret_cast<const char*>(values.data()),
            static_cast<std::streamsize>(values.size() * sizeof(T)));
}

// An array of at most `largest` values, and no more than the file still holds (a damaged count
// is refused before anything is allocated for it).
template <class T>
void read_array(std::ifstream& in, std::vector<T>& values, std::uint64_t largest,
                const std::string& path) {
  std::uint64_t count = 0;
  read(in, count, path);
  const auto here = in.tellg();
  in.seekg(0, std::ios::end);
  const auto left = static_cast<std::uint64_t>(in.tellg() - here);
  in.seekg(here);
  if (count > largest || count > left / sizeof(T)) {
    throw std::runtime_error("load_state: bad pressure set-up in " + path);
  }
  values.resize(count);
  in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(count * sizeof(T)));
  if (!in) throw std::runtime_error("load_state: truncated file " + path);
}

void write_setup(std::ofstream& out, const PressureSetupState& setup) {
  write(out, static_cast<std::uint8_t>(setup.kept ? 1 : 0));
  if (!setup.kept) return;
  for (const std::int32_t count :
       {setup.age, setup.base_iterations, setup.last_iterations, setup.aggregate_count}) {
    write(out, count);
  }
  write_array(out, setup.aggregate_of_key);
  write_array(out, setup.coarse_row);
  write_array(out, setup.coarse_column);
  write_array(out, setup.coarse_value);
}

// The set-up after the particles; each array no longer than the file holds, and the whole
// consistent (find_setup_problem).
void read_setup(std::ifstream& in, PressureSetupState& setup, std::uint64_t particles,
                const std::string& path) {
  std::uint8_t kept = 0;
  read(in, kept, path);
  if (kept == 0) return;
  std::int32_t counts[4];
  for (std::int32_t& count : counts) read(in, count, path);
  setup.kept = true;
  setup.age = counts[0];
  setup.base_iterations = counts[1];
  setup.last_iterations = counts[2];
  setup.aggregate_count = counts[3];
  const std::uint64_t count = static_cast<std::uint64_t>(std::max(counts[3], 0));
  read_array(in, setup.aggregate_of_key, particles, path);
  read_array(in, setup.coarse_row, count * count, path);
  read_array(in, setup.coarse_column, count * count, path);
  read_array(in, setup.coarse_value, count * count, path);
  if (const auto problem = find_setup_problem(setup, particles)) {
    throw std::runtime_error("load_state: bad pressure set-up in " + path + ": " + problem->field +
                             " " + problem->what);
  }
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
  write_setup(out, state.pressure_setup);
  if (!out) throw std::runtime_error("save_state: write failed for " + path);
}

MpsState load_state(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("load_state: cannot open " + path);
  char magic[8];
  in.read(magic, sizeof(magic));
  std::uint32_t version = 0;
  read(in, version, path);
  // Version 1 had no pressure set-up: read as one without a set-up in reuse.
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0 || (version != 1 && version != kVersion)) {
    throw std::runtime_error("load_state: " + path + " is not a fluid_mps restart file (v1, v2)");
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
  if (version >= 2) read_setup(in, state.pressure_setup, n, path);
  return state;
}

}  // namespace cosim::mps
