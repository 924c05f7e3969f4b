#include "cosim/output/point_series.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;
using cosim::output::count_point_frames;
using cosim::output::PointFrame;
using cosim::output::PointSeriesWriter;
using cosim::output::read_point_frame;

namespace {

// A fresh directory per test so parallel ctest runs never share files.
class PointSeriesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("cosim_output_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// Values that do not survive a decimal round trip, to prove the storage is bit-exact.
PointFrame make_frame(int n, double time, unsigned seed, bool with_segments) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  PointFrame f;
  f.time = time;
  for (int i = 0; i < n; ++i) {
    f.positions.emplace_back(u(rng), u(rng), std::nextafter(u(rng), 0.0));
    f.scalars["pressure"].push_back(u(rng) / 3.0);
    f.scalars["density"].push_back(i == 0 ? std::numeric_limits<double>::denorm_min() : u(rng));
    f.vectors["velocity"].emplace_back(u(rng), u(rng), u(rng));
    f.labels["kind"].push_back(i % 3);
    f.labels["plant"].push_back(i == 1 ? std::numeric_limits<int>::min() : -i);
  }
  if (with_segments) {
    for (int i = 0; i + 1 < n; ++i) f.segments.push_back({i, i + 1});
  }
  return f;
}

bool bits_equal(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

void expect_frames_equal(const PointFrame& a, const PointFrame& b) {
  EXPECT_TRUE(bits_equal(a.time, b.time));
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (std::size_t i = 0; i < a.positions.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(bits_equal(a.positions[i][k], b.positions[i][k]));
  }
  ASSERT_EQ(a.scalars.size(), b.scalars.size());
  for (const auto& [name, values] : a.scalars) {
    ASSERT_TRUE(b.scalars.count(name)) << name;
    const auto& other = b.scalars.at(name);
    ASSERT_EQ(values.size(), other.size());
    for (std::size_t i = 0; i < values.size(); ++i) EXPECT_TRUE(bits_equal(values[i], other[i]));
  }
  ASSERT_EQ(a.vectors.size(), b.vectors.size());
  for (const auto& [name, values] : a.vectors) {
    ASSERT_TRUE(b.vectors.count(name)) << name;
    const auto& other = b.vectors.at(name);
    ASSERT_EQ(values.size(), other.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(bits_equal(values[i][k], other[i][k]));
    }
  }
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_EQ(a.segments, b.segments);
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Minimal XML check: every start tag is closed in order (no attributes with '>' in them here).
bool tags_balanced(const std::string& xml) {
  std::vector<std::string> stack;
  std::regex tag(R"(<(/?)([A-Za-z_][\w:.-]*)[^>]*?(/?)>)");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), tag); it != std::sregex_iterator();
       ++it) {
    const auto& m = *it;
    if (m[3] == "/") continue;  // self-closing
    if (m[1] == "/") {
      if (stack.empty() || stack.back() != m[2]) return false;
      stack.pop_back();
    } else {
      stack.push_back(m[2]);
    }
  }
  return stack.empty();
}

std::size_t count_of(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto pos = text.find(needle); pos != std::string::npos; pos = text.find(needle, pos + 1)) {
    ++n;
  }
  return n;
}

// Raw read of a 1D double dataset; empty on any failure so the assertion shows the difference.
std::vector<double> read_raw(const fs::path& file, const std::string& dataset) {
  std::vector<double> out;
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_file_locking(fapl, false, true);
  hid_t f = H5Fopen(file.string().c_str(), H5F_ACC_RDONLY, fapl);
  H5Pclose(fapl);
  if (f < 0) return out;
  hid_t d = H5Dopen2(f, dataset.c_str(), H5P_DEFAULT);
  if (d >= 0) {
    hid_t space = H5Dget_space(d);
    out.resize(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    if (H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0) out.clear();
    H5Sclose(space);
    H5Dclose(d);
  }
  H5Fclose(f);
  return out;
}

}  // namespace

TEST_F(PointSeriesTest, RoundTripsFramesOfVaryingSizeBitExact) {
  std::vector<PointFrame> written{make_frame(5, 0.0, 1, false), make_frame(17, 0.1, 2, true),
                                  make_frame(1, 0.2 + 1e-17, 3, false),
                                  make_frame(40, 1.0 / 3.0, 4, true)};
  {
    PointSeriesWriter writer(dir_ / "run", "round trip");
    for (const auto& f : written) writer.write_frame(f);
    EXPECT_EQ(writer.frame_count(), 4);
    EXPECT_EQ(writer.h5_path(), dir_ / "run.h5");
    EXPECT_EQ(writer.xdmf_path(), dir_ / "run.xmf");
    // Readable while the writer still holds the file open.
    EXPECT_EQ(count_point_frames(writer.h5_path()), 4);
    expect_frames_equal(written[1], read_point_frame(writer.h5_path(), 1));
  }
  ASSERT_EQ(count_point_frames(dir_ / "run.h5"), 4);
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    expect_frames_equal(written[static_cast<std::size_t>(i)], read_point_frame(dir_ / "run.h5", i));
  }
  expect_frames_equal(written[3], read_point_frame(dir_ / "run.h5", -1));
  expect_frames_equal(written[0], read_point_frame(dir_ / "run.h5", -4));
}

TEST_F(PointSeriesTest, RoundTripsEmptyAndFieldlessFrames) {
  PointFrame bare;
  bare.time = 2.5;
  bare.positions = {{1, 2, 3}, {4, 5, 6}};
  PointFrame empty;
  empty.time = 3.0;
  {
    PointSeriesWriter writer(dir_ / "bare", "bare");
    writer.write_frame(bare);
    writer.write_frame(empty);
  }
  expect_frames_equal(bare, read_point_frame(dir_ / "bare.h5", 0));
  expect_frames_equal(empty, read_point_frame(dir_ / "bare.h5", 1));
}

TEST_F(PointSeriesTest, SeriesRoundTripAndOverwrite) {
  const fs::path stem = dir_ / "series";
  {
    PointSeriesWriter writer(stem, "series");
    writer.write_series("tip_deflection", {0.0, 0.5, 1.0}, {0.0, 0.1, 0.3});
    writer.write_series("front", {0.0}, {1.0});
    writer.write_series("tip_deflection", {0.0, 0.5}, {0.0, 1.0 / 7.0});  // overwrite, shorter
    writer.write_frame(make_frame(3, 0.0, 9, false));
    EXPECT_THROW(writer.write_series("bad", {0.0, 1.0}, {1.0}), std::invalid_argument);
    EXPECT_THROW(writer.write_series("a/b", {0.0}, {1.0}), std::invalid_argument);
  }
  const fs::path h5 = stem.string() + ".h5";
  EXPECT_EQ(read_raw(h5, "/series/tip_deflection/time"), (std::vector<double>{0.0, 0.5}));
  EXPECT_EQ(read_raw(h5, "/series/tip_deflection/values"), (std::vector<double>{0.0, 1.0 / 7.0}));
  EXPECT_EQ(read_raw(h5, "/series/front/time"), (std::vector<double>{0.0}));
  EXPECT_EQ(read_raw(h5, "/series/front/values"), (std::vector<double>{1.0}));
  EXPECT_TRUE(read_raw(h5, "/series/bad/time").empty());  // rejected before writing
  // Series do not count as frames and do not disturb them.
  EXPECT_EQ(count_point_frames(h5), 1);
  expect_frames_equal(make_frame(3, 0.0, 9, false), read_point_frame(stem.string() + ".h5", 0));
}

TEST_F(PointSeriesTest, XdmfIsWellFormedAndReferencesExistingDatasets) {
  const fs::path stem = dir_ / "view";
  std::vector<PointFrame> written{make_frame(4, 0.0, 1, false), make_frame(6, 0.25, 2, true),
                                  make_frame(2, 0.5, 3, false)};
  PointSeriesWriter writer(stem, "river <demo> & co");
  for (const auto& f : written) writer.write_frame(f);
  const std::string xml = slurp(writer.xdmf_path());
  ASSERT_FALSE(fs::exists(stem.string() + ".xmf.tmp"));
  EXPECT_TRUE(tags_balanced(xml)) << xml;
  EXPECT_NE(xml.find("CollectionType=\"Temporal\""), std::string::npos);
  EXPECT_NE(xml.find("river &lt;demo&gt; &amp; co"), std::string::npos);
  // Outer temporal + 3 frames + (points, segments) for the chain frame.
  EXPECT_EQ(count_of(xml, "<Grid "), 6u);
  EXPECT_EQ(count_of(xml, "<Time "), 5u);
  EXPECT_EQ(count_of(xml, "TopologyType=\"Polyline\""), 1u);
  EXPECT_EQ(count_of(xml, "TopologyType=\"Polyvertex\""), 3u);
  for (const char* name : {"pressure", "density", "velocity", "kind", "plant"}) {
    EXPECT_EQ(count_of(xml, "<Attribute Name=\"" + std::string(name) + "\""), 4u) << name;
  }

  // Every DataItem points into run.h5 by relative name, at a dataset the reader finds with the
  // advertised size.
  std::regex item(
      R"re(<DataItem Dimensions="(\d+)(?: (\d+))?"[^>]*>([^:<]+):/frames/(\d+)/([^<]+)</DataItem>)re");
  int items = 0;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), item); it != std::sregex_iterator();
       ++it, ++items) {
    const auto& m = *it;
    EXPECT_EQ(m[3].str(), "view.h5");
    const std::size_t rows = std::stoul(m[1]);
    const PointFrame f = read_point_frame(writer.h5_path(), std::stoi(m[4]));
    const std::string path = m[5];
    const auto slash = path.find('/');
    const std::string kind = path.substr(0, slash);
    const std::string name = slash == std::string::npos ? "" : path.substr(slash + 1);
    if (kind == "positions") {
      EXPECT_EQ(rows, f.positions.size());
      EXPECT_EQ(m[2].str(), "3");
    } else if (kind == "segments") {
      EXPECT_EQ(rows, f.segments.size());
      EXPECT_EQ(m[2].str(), "2");
    } else if (kind == "scalars") {
      ASSERT_TRUE(f.scalars.count(name)) << path;
      EXPECT_EQ(rows, f.scalars.at(name).size());
    } else if (kind == "vectors") {
      ASSERT_TRUE(f.vectors.count(name)) << path;
      EXPECT_EQ(rows, f.vectors.at(name).size());
      EXPECT_EQ(m[2].str(), "3");
    } else if (kind == "labels") {
      ASSERT_TRUE(f.labels.count(name)) << path;
      EXPECT_EQ(rows, f.labels.at(name).size());
    } else {
      ADD_FAILURE() << "unexpected dataset " << path;
    }
  }
  // Per Uniform grid: geometry + 5 attributes, plus the segment connectivity.
  EXPECT_EQ(items, 4 * 6 + 1);
}

TEST_F(PointSeriesTest, XdmfIsRewrittenAfterEveryFrame) {
  PointSeriesWriter writer(dir_ / "grow", "grow");
  EXPECT_TRUE(tags_balanced(slurp(writer.xdmf_path())));
  for (int i = 0; i < 3; ++i) {
    writer.write_frame(make_frame(2 + i, i, static_cast<unsigned>(i), false));
    const std::string xml = slurp(writer.xdmf_path());
    EXPECT_TRUE(tags_balanced(xml));
    EXPECT_EQ(count_of(xml, "<Grid "), static_cast<std::size_t>(i + 2));
  }
}

TEST_F(PointSeriesTest, ErrorsNameTheFileAndTheIndex) {
  const fs::path missing = dir_ / "nope.h5";
  try {
    read_point_frame(missing, 0);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nope.h5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(count_point_frames(missing), std::runtime_error);

  {
    PointSeriesWriter writer(dir_ / "two", "two");
    writer.write_frame(make_frame(3, 0.0, 1, false));
    writer.write_frame(make_frame(3, 1.0, 2, false));
  }
  for (int bad : {2, 5, -3}) {
    try {
      read_point_frame(dir_ / "two.h5", bad);
      FAIL() << "expected an exception for " << bad;
    } catch (const std::out_of_range& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("two.h5"), std::string::npos) << what;
      EXPECT_NE(what.find(std::to_string(bad)), std::string::npos) << what;
      EXPECT_NE(what.find("2 frames"), std::string::npos) << what;
    }
  }

  // Not an HDF5 file: the HDF5 failure becomes an exception naming the file.
  std::ofstream(dir_ / "text.h5") << "not hdf5";
  try {
    count_point_frames(dir_ / "text.h5");
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("text.h5"), std::string::npos) << e.what();
  }
}

TEST_F(PointSeriesTest, RejectsInconsistentFramesWithoutCorruptingTheFile) {
  PointSeriesWriter writer(dir_ / "bad", "bad");
  writer.write_frame(make_frame(3, 0.0, 1, true));
  PointFrame wrong = make_frame(3, 1.0, 2, false);
  wrong.scalars["pressure"].pop_back();
  EXPECT_THROW(writer.write_frame(wrong), std::invalid_argument);
  PointFrame bad_segment = make_frame(3, 1.0, 2, false);
  bad_segment.segments.push_back({0, 3});
  EXPECT_THROW(writer.write_frame(bad_segment), std::invalid_argument);
  PointFrame bad_name = make_frame(3, 1.0, 2, false);
  bad_name.labels["a/b"] = {0, 0, 0};
  EXPECT_THROW(writer.write_frame(bad_name), std::invalid_argument);
  EXPECT_EQ(writer.frame_count(), 1);
  writer.write_frame(make_frame(4, 2.0, 3, false));
  EXPECT_EQ(count_point_frames(writer.h5_path()), 2);
  expect_frames_equal(make_frame(4, 2.0, 3, false), read_point_frame(writer.h5_path(), 1));
}

TEST_F(PointSeriesTest, WriterDestroyedMidRunLeavesReadableFile) {
  const fs::path stem = dir_ / "unwound";
  try {
    PointSeriesWriter writer(stem, "unwound");
    for (int i = 0; i < 10; ++i) {
      if (i == 3) throw std::runtime_error("solver diverged");
      writer.write_frame(make_frame(5 + i, 0.1 * i, static_cast<unsigned>(i), i % 2 == 1));
    }
  } catch (const std::runtime_error&) {
  }
  ASSERT_EQ(count_point_frames(stem.string() + ".h5"), 3);
  expect_frames_equal(make_frame(7, 0.2, 2, false), read_point_frame(stem.string() + ".h5", -1));
  EXPECT_EQ(count_of(slurp(stem.string() + ".xmf"), "<Time "),
            5u);  // frame 1 has segments: 3 Times
}

TEST_F(PointSeriesTest, KilledWriterLeavesFileReadableUpToLastFrame) {
  const fs::path stem = dir_ / "killed";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // No destructor, no H5Fclose: only the per-frame flush protects the data.
    auto* writer = new PointSeriesWriter(stem, "killed");
    for (int i = 0; i < 3; ++i) {
      writer->write_frame(make_frame(10 + i, i, static_cast<unsigned>(i), true));
    }
    writer->write_series("tip", {0.0, 1.0}, {0.5, 0.25});
    ::raise(SIGKILL);
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  ASSERT_EQ(count_point_frames(stem.string() + ".h5"), 3);
  for (int i = 0; i < 3; ++i) {
    expect_frames_equal(make_frame(10 + i, i, static_cast<unsigned>(i), true),
                        read_point_frame(stem.string() + ".h5", i));
  }
  EXPECT_TRUE(tags_balanced(slurp(stem.string() + ".xmf")));
  EXPECT_EQ(read_raw(stem.string() + ".h5", "/series/tip/values"),
            (std::vector<double>{0.5, 0.25}));
}
