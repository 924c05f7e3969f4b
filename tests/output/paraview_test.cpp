// ParaView opens the XDMF index with each of its XDMF readers and sees every point as a vertex
// cell, every segment as a line and the frame values as field data. Skips without pvpython
// (Debian package paraview; not required by CI).
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cosim/output/point_series.hpp"

namespace fs = std::filesystem;
using cosim::output::PointFrame;
using cosim::output::PointSeriesWriter;

namespace {

// COSIM_PVPYTHON, else pvpython on the PATH; empty when there is none.
std::string find_pvpython() {
  if (const char* chosen = std::getenv("COSIM_PVPYTHON"); chosen != nullptr && *chosen != 0) {
    return chosen;
  }
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / "pvpython";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return "";
}

PointFrame cloud(int n, double time) {
  PointFrame f;
  f.time = time;
  for (int i = 0; i < n; ++i) {
    f.positions.emplace_back(0.1 * i, 0.01 * i * i, time);
    f.scalars["pressure"].push_back(100.0 * i);
    f.vectors["velocity"].emplace_back(i, 0, 0);
    f.labels["kind"].push_back(i % 2);
  }
  return f;
}

}  // namespace

TEST(ParaView, EveryXdmfReaderShowsPointsSegmentsAndFieldData) {
  const std::string pvpython = find_pvpython();
  if (pvpython.empty()) GTEST_SKIP() << "pvpython not found (Debian package paraview)";
  const fs::path dir = fs::temp_directory_path() / ("cosim_paraview_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    PointSeriesWriter writer(dir / "cloud", "paraview check");
    writer.describe("pressure", {"Pa", "pressure", ""});
    writer.describe("kind", {"1", "kind", "0 even, 1 odd"});
    writer.write_frame(cloud(5, 0.0));
    writer.write_frame(cloud(7, 0.5));
    PointFrame chain = cloud(4, 1.0);
    chain.segments = {{0, 1}, {1, 2}, {2, 3}};
    writer.write_frame(chain);
    writer.write_series("tip", {0.0, 1.0}, {2.0, 4.0});
  }
  // Per time step: points, segments, and the field data the frame must carry.
  std::ofstream(dir / "expected.json") << R"({
    "point_arrays": ["pressure", "velocity", "kind"],
    "steps": [
      {"time": 0.0, "points": 5, "segments": 0, "field": {"frame_points": 5, "tip": 2.0}},
      {"time": 0.5, "points": 7, "segments": 0, "field": {"frame_points": 7, "tip": 3.0}},
      {"time": 1.0, "points": 4, "segments": 3, "field": {"frame_points": 4, "tip": 4.0}}
    ]})";
  const std::string command = "'" + pvpython + "' '" + COSIM_PARAVIEW_PROBE + "' '" +
                              (dir / "cloud.xmf").string() + "' '" +
                              (dir / "expected.json").string() + "' 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) output += buffer.data();
  const int status = ::pclose(pipe);
  fs::remove_all(dir);
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 77) GTEST_SKIP() << "ParaView's Python modules are unusable:\n" << output;
  EXPECT_EQ(code, 0) << output;
}
