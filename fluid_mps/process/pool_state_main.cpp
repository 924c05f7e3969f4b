// fishway_pool_state: keeps one pool of a pool_fishway run's output frame, the particles a
// periodic_pool scene's `chain_state` reads (its fluid, and the walls and dummies it checks the
// geometry with), in chain coordinates, as a one-frame particles file a bundle can carry.
//
//   fishway_pool_state RUN/fluid_mps/particles.h5 --time 6 --pool 3 --particle-spacing 0.00666
//       --pool-length 0.3 --out scenarios/fishway_periodic_pool/chain_pool3_t6
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>

#include "cosim/coupler/frame.hpp"
#include "cosim/fluid_mps/pool_state.hpp"
#include "cosim/output/point_series.hpp"

namespace {

using namespace cosim;

int nearest_frame(const std::filesystem::path& file, double time) {
  const int nearest = output::nearest_point_frame(file, time);
  if (nearest < 0) throw std::runtime_error(file.string() + " holds no frames");
  return nearest;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"keep one pool of a pool_fishway frame for a periodic_pool's chain_state"};
  std::filesystem::path input, out;
  double time = 0.0, spacing = 0.0, tolerance = 0.01;
  mps::FishwayGeometry geometry;
  int pool = 1;
  app.add_option("particles", input, "particles.h5 of a pool_fishway run")->required();
  app.add_option("--time", time, "of the frame [s]")->required();
  app.add_option("--time-tolerance", tolerance, "the nearest frame must lie this close [s]");
  app.add_option("--pool", pool, "counted from 1 at the inflow")->required();
  app.add_option("--particle-spacing", spacing, "l0 of the run [m]")->required();
  app.add_option("--pool-length", geometry.pool_length, "crest to crest [m]")->required();
  app.add_option("--out", out, "file stem: writes STEM.h5 and STEM.xmf")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    const int index = nearest_frame(input, time);
    const output::PointFrame frame = output::read_point_frame(input, index);
    if (std::abs(frame.time - time) > tolerance) {
      throw std::runtime_error(
          fmt::format("no frame within {} s of {} s (nearest {} s)", tolerance, time, frame.time));
    }
    const coupler::SolverFrame world(2, 1.0);
    mps::MpsState state;
    state.time = frame.time;
    for (const auto& x : frame.positions) state.positions.push_back(world.to_solver(x));
    for (const auto& u : frame.vectors.at("velocity")) {
      state.velocities.push_back(world.to_solver(u));
    }
    state.pressures = frame.scalars.at("pressure");
    for (const int kind : frame.labels.at("kind")) {
      state.kinds.push_back(static_cast<mps::ParticleKind>(kind));
    }
    const auto kept = mps::extract_chain_pool(state, mps::chain_pool(spacing, geometry, pool));
    output::PointFrame result;
    result.time = kept.time;
    for (std::size_t i = 0; i < kept.positions.size(); ++i) {
      result.positions.push_back(world.to_world(kept.positions[i]));
      result.vectors["velocity"].push_back(world.to_world(kept.velocities[i]));
      result.scalars["pressure"].push_back(kept.pressures[i]);
      result.labels["kind"].push_back(static_cast<int>(kept.kinds[i]));
    }
    output::PointSeriesWriter writer(out, "fluid_mps");
    writer.describe("velocity", {"m/s", "particle velocity (world frame)", ""});
    writer.describe("pressure", {"Pa", "particle pressure", ""});
    writer.describe("kind", {"1", "particle kind", "0 fluid, 1 wall, 2 dummy, 3 inactive"});
    writer.write_frame(result);
    std::cout << fmt::format("{}: pool {} of frame {} (t = {:.9g} s), {} of {} particles\n",
                             writer.h5_path().string(), pool, index, frame.time,
                             result.positions.size(), frame.positions.size());
  } catch (const std::exception& error) {
    std::cerr << "fishway_pool_state: " << error.what() << '\n';
    return 1;
  }
  return 0;
}
