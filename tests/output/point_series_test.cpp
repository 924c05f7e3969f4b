#include "cosim/output/point_series.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <cmath>
#include <limits>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;
using cosim::output::count_point_frames;
using cosim::output::FieldInfo;
using cosim::output::PointFrame;
using cosim::output::PointSeriesWriter;
using cosim::output::read_field_info;
using cosim::output::read_point_frame;
using cosim::output::read_series;
using cosim::output::Series;
using cosim::output::SeriesInfo;

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

// Every dataset of a file, by full path.
std::vector<std::string> datasets_of(const fs::path& file) {
  std::vector<std::string> names;
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_file_locking(fapl, false, true);
  hid_t f = H5Fopen(file.string().c_str(), H5F_ACC_RDONLY, fapl);
  H5Pclose(fapl);
  if (f < 0) return names;
  struct Visit {
    hid_t file;
    std::vector<std::string>* names;
  } visit{f, &names};
  H5Lvisit(
      f, H5_INDEX_NAME, H5_ITER_INC,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        auto* v = static_cast<Visit*>(data);
        hid_t object = H5Oopen(v->file, name, H5P_DEFAULT);
        if (object >= 0) {
          if (H5Iget_type(object) == H5I_DATASET) v->names->push_back(std::string("/") + name);
          H5Oclose(object);
        }
        return 0;
      },
      &visit);
  H5Fclose(f);
  return names;
}

const Series* find_series(const std::vector<Series>& all, const std::string& name) {
  for (const auto& s : all) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

// The value of the Grid-centred attribute `name` in each frame grid of an XDMF file, in order;
// NaN where a frame has none.
std::vector<double> grid_values(const std::string& xml, const std::string& name) {
  std::vector<double> values;
  std::regex grid(R"re(<Grid Name="(frame_\d+|points)" GridType="Uniform">([\s\S]*?)</Grid>)re");
  const std::regex value(
      "<Attribute Name=\"" + name +
      R"re(" AttributeType="Scalar" Center="Grid">\s*<DataItem[^>]*Format="XML">([^<]+)</DataItem>)re");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), grid); it != std::sregex_iterator();
       ++it) {
    const std::string body = (*it)[2];
    std::smatch m;
    values.push_back(std::regex_search(body, m, value) ? std::stod(m[1])
                                                       : std::numeric_limits<double>::quiet_NaN());
  }
  return values;
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

TEST_F(PointSeriesTest, FindsTheFrameNearestToATimeFromTheFrameTimesAlone) {
  {
    PointSeriesWriter writer(dir_ / "times", "times");
    for (const double t : {0.0, 0.1, 0.2, 0.35, 0.5})
      writer.write_frame(make_frame(3, t, 1, false));
  }
  const auto file = dir_ / "times.h5";
  EXPECT_EQ(cosim::output::read_point_frame_time(file, 3), 0.35);
  EXPECT_THROW(cosim::output::read_point_frame_time(file, 5), std::out_of_range);
  EXPECT_EQ(cosim::output::nearest_point_frame(file, -1.0), 0);
  EXPECT_EQ(cosim::output::nearest_point_frame(file, 0.14), 1);
  EXPECT_EQ(cosim::output::nearest_point_frame(file, 0.16), 2);
  EXPECT_EQ(cosim::output::nearest_point_frame(file, 0.3), 3);
  EXPECT_EQ(cosim::output::nearest_point_frame(file, 9.0), 4);
  { PointSeriesWriter writer(dir_ / "none", "none"); }
  EXPECT_EQ(cosim::output::nearest_point_frame(dir_ / "none.h5", 0.0), -1);
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
  // One frame has segments, so every frame is a spatial collection (the legacy Xdmf reader
  // needs one data type in all steps): outer temporal + 3 collections + 3 point grids + the
  // chain frame's segment grid; a Time in each collection and each grid under it.
  EXPECT_EQ(count_of(xml, "<Grid "), 8u);
  EXPECT_EQ(count_of(xml, "<Time "), 7u);
  EXPECT_EQ(count_of(xml, "CollectionType=\"Spatial\""), 3u);
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
  // Frame 1 has segments, so all three are collections: 2 Times each, 3 for frame 1.
  EXPECT_EQ(count_of(slurp(stem.string() + ".xmf"), "<Time "), 7u);
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

TEST_F(PointSeriesTest, EveryDatasetCarriesUnitAndDescriptionAndLabelsTheirLegend) {
  const fs::path stem = dir_ / "described";
  {
    PointSeriesWriter writer(stem, "described");
    writer.describe("pressure", {"Pa", "pressure solved by the Poisson equation", ""});
    writer.describe("velocity", {"m/s", "particle velocity", ""});
    writer.describe("kind", {"1", "particle kind", "0 fluid, 1 wall, 2 dummy"});
    EXPECT_THROW(writer.describe("a/b", {}), std::invalid_argument);
    writer.write_frame(make_frame(4, 0.0, 1, true));  // density and plant stay undescribed
    writer.write_frame(make_frame(3, 0.5, 2, false));
    writer.write_series("tip", {0.0, 0.5}, {0.1, 0.2}, {"m", "tip displacement", {}, {}, ""});
    writer.write_series("bare", {0.0}, {1.0});
  }
  const fs::path h5 = stem.string() + ".h5";
  const auto names = datasets_of(h5);
  ASSERT_GT(names.size(), 20u);
  for (const auto& name : names) {
    SCOPED_TRACE(name);
    const FieldInfo info = read_field_info(h5, name);
    EXPECT_FALSE(info.unit.empty());
    EXPECT_FALSE(info.description.empty());
  }
  auto info = [&](const std::string& dataset) { return read_field_info(h5, dataset); };
  EXPECT_EQ(info("/frames/000000/positions").unit, "m");
  EXPECT_EQ(info("/frames/000001/scalars/pressure").unit, "Pa");
  EXPECT_EQ(info("/frames/000001/scalars/pressure").description,
            "pressure solved by the Poisson equation");
  EXPECT_EQ(info("/frames/000000/vectors/velocity").unit, "m/s");
  EXPECT_EQ(info("/frames/000000/labels/kind").legend, "0 fluid, 1 wall, 2 dummy");
  EXPECT_EQ(info("/frames/000000/labels/kind").description, "particle kind");
  // Undescribed fields say so and name themselves; labels are dimensionless.
  EXPECT_EQ(info("/frames/000000/scalars/density").unit, "unspecified");
  EXPECT_NE(info("/frames/000000/scalars/density").description.find("density"), std::string::npos);
  EXPECT_EQ(info("/frames/000000/labels/plant").unit, "1");
  EXPECT_TRUE(info("/frames/000000/labels/plant").legend.empty());
  EXPECT_EQ(info("/frames/000000/segments").unit, "1");
  EXPECT_EQ(info("/series/tip/time").unit, "s");
  EXPECT_EQ(info("/series/tip/values").unit, "m");
  EXPECT_EQ(info("/series/tip/values").description, "tip displacement");
  EXPECT_EQ(info("/series/bare/values").unit, "unspecified");
  // Statistics inherit the unit of their field.
  EXPECT_EQ(info("/series/frame_pressure_max/values").unit, "Pa");
  EXPECT_EQ(info("/series/frame_velocity_max_magnitude/values").unit, "m/s");
}

TEST_F(PointSeriesTest, FramesFillTheSeriesGroupWithTheirStatistics) {
  const fs::path stem = dir_ / "statistics";
  PointFrame a;
  a.time = 0.0;
  a.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  a.scalars["pressure"] = {1.0, -2.0, 4.0};
  a.vectors["velocity"] = {{3, 4, 0}, {0, 0, 1}, {0, 0, 0}};
  PointFrame b = a;
  b.time = 0.25;
  b.positions.pop_back();
  b.scalars["pressure"] = {10.0, 20.0};
  b.vectors["velocity"] = {{0, 0, 0}, {0, 12, 5}};
  PointFrame empty;
  empty.time = 0.5;
  // NaN is a value not computed for that point: left out of the statistics, NaN if none has one.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PointFrame partial = a;
  partial.time = 0.75;
  partial.scalars["pressure"] = {nan, 6.0, -1.0};
  PointFrame none = a;
  none.time = 1.0;
  none.scalars["pressure"] = {nan, nan, nan};
  {
    PointSeriesWriter writer(stem, "statistics");
    writer.write_frame(a);
    writer.write_frame(b);
    writer.write_frame(empty);
    writer.write_frame(partial);
    writer.write_frame(none);
    EXPECT_THROW(writer.write_series("frame_points", {0.0}, {1.0}), std::invalid_argument);
  }
  const auto all = read_series(stem.string() + ".h5");
  const auto* points = find_series(all, "frame_points");
  ASSERT_NE(points, nullptr);
  EXPECT_EQ(points->times, (std::vector<double>{0.0, 0.25, 0.5, 0.75, 1.0}));
  EXPECT_EQ(points->values, (std::vector<double>{3, 2, 0, 3, 3}));
  const auto* low = find_series(all, "frame_pressure_min");
  const auto* high = find_series(all, "frame_pressure_max");
  const auto* mean = find_series(all, "frame_pressure_mean");
  const auto* speed = find_series(all, "frame_velocity_max_magnitude");
  ASSERT_TRUE(low && high && mean && speed);
  ASSERT_EQ(low->values.size(), 4u);
  ASSERT_EQ(high->values.size(), 4u);
  ASSERT_EQ(mean->values.size(), 4u);
  const std::vector<double> lows(low->values.begin(), low->values.begin() + 3);
  const std::vector<double> highs(high->values.begin(), high->values.begin() + 3);
  const std::vector<double> means(mean->values.begin(), mean->values.begin() + 3);
  EXPECT_EQ(lows, (std::vector<double>{-2.0, 10.0, -1.0}));
  EXPECT_EQ(highs, (std::vector<double>{4.0, 20.0, 6.0}));
  EXPECT_EQ(means, (std::vector<double>{1.0, 15.0, 2.5}));
  EXPECT_TRUE(std::isnan(low->values[3]) && std::isnan(high->values[3]) &&
              std::isnan(mean->values[3]));
  EXPECT_EQ(speed->values, (std::vector<double>{5.0, 13.0, 5.0, 5.0}));
  EXPECT_EQ(speed->times, (std::vector<double>{0.0, 0.25, 0.75, 1.0}));
  EXPECT_EQ(all.size(), 5u);
}

TEST_F(PointSeriesTest, SeriesKeepTheirReferenceAndSource) {
  const fs::path stem = dir_ / "reference";
  {
    PointSeriesWriter writer(stem, "reference");
    SeriesInfo info;
    info.unit = "m";
    info.description = "surge front position";
    info.reference_times = {0.0, 1.0, 2.0};
    info.reference_values = {0.1, 0.3, 0.6};
    info.reference_source = "Martin & Moyce (1952)";
    writer.write_series("front", {0.0, 0.5}, {0.1, 0.2}, info);
    info.reference_values.pop_back();
    EXPECT_THROW(writer.write_series("bad", {0.0}, {0.0}, info), std::invalid_argument);
  }
  const auto all = read_series(stem.string() + ".h5");
  const auto* front = find_series(all, "front");
  ASSERT_NE(front, nullptr);
  EXPECT_EQ(front->times, (std::vector<double>{0.0, 0.5}));
  EXPECT_EQ(front->values, (std::vector<double>{0.1, 0.2}));
  EXPECT_EQ(front->info.unit, "m");
  EXPECT_EQ(front->info.description, "surge front position");
  EXPECT_EQ(front->info.reference_times, (std::vector<double>{0.0, 1.0, 2.0}));
  EXPECT_EQ(front->info.reference_values, (std::vector<double>{0.1, 0.3, 0.6}));
  EXPECT_EQ(front->info.reference_source, "Martin & Moyce (1952)");
  EXPECT_EQ(find_series(all, "bad"), nullptr);
  EXPECT_EQ(read_field_info(stem.string() + ".h5", "/series/front/reference_values").unit, "m");
}

TEST_F(PointSeriesTest, XdmfPointsHaveExplicitVertexConnectivity) {
  const fs::path stem = dir_ / "cells";
  PointSeriesWriter writer(stem, "cells");
  writer.write_frame(make_frame(4, 0.0, 1, false));
  writer.write_frame(make_frame(6, 0.25, 2, true));
  writer.write_frame(make_frame(4, 0.5, 3, false));
  const std::string xml = slurp(writer.xdmf_path());
  EXPECT_TRUE(tags_balanced(xml)) << xml;
  // Every Polyvertex topology lists its cells: 0..n-1 from a dataset of n entries.
  std::regex topology(
      R"re(<Topology TopologyType="Polyvertex" NumberOfElements="(\d+)" NodesPerElement="1">\s*<DataItem Dimensions="(\d+)" NumberType="Int" Precision="4" Format="HDF">cells\.h5:([^<]+)</DataItem>\s*</Topology>)re");
  int found = 0;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), topology);
       it != std::sregex_iterator(); ++it, ++found) {
    const std::size_t n = std::stoul((*it)[1]);
    EXPECT_EQ(std::stoul((*it)[2]), n);
    const FieldInfo info = read_field_info(writer.h5_path(), (*it)[3]);
    EXPECT_EQ(info.unit, "1");
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(fapl, false, true);
    hid_t f = H5Fopen(writer.h5_path().string().c_str(), H5F_ACC_RDONLY, fapl);
    H5Pclose(fapl);
    ASSERT_GE(f, 0);
    hid_t d = H5Dopen2(f, (*it)[3].str().c_str(), H5P_DEFAULT);
    ASSERT_GE(d, 0);
    hid_t space = H5Dget_space(d);
    std::vector<int> cells(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    H5Dread(d, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, cells.data());
    H5Sclose(space);
    H5Dclose(d);
    H5Fclose(f);
    ASSERT_EQ(cells.size(), n);
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(cells[i], static_cast<int>(i));
  }
  EXPECT_EQ(found, 3);
  EXPECT_EQ(count_of(xml, "TopologyType=\"Polyvertex\""), 3u);
  // Frames of the same size share one connectivity dataset.
  EXPECT_EQ(count_of(xml, "cells.h5:/topology/polyvertex_4<"), 2u);
}

TEST_F(PointSeriesTest, XdmfFramesCarryStatisticsAndSeriesAsGridValues) {
  const fs::path stem = dir_ / "grid";
  PointSeriesWriter writer(stem, "grid");
  writer.write_frame(make_frame(4, 0.0, 1, false));
  writer.write_frame(make_frame(6, 0.25, 2, true));
  writer.write_frame(make_frame(5, 0.5, 3, false));
  EXPECT_EQ(grid_values(slurp(writer.xdmf_path()), "frame_points"), (std::vector<double>{4, 6, 5}));
  // A series written at the end is indexed into the frames already written: its samples at
  // the frame times, linear between samples, nothing outside the sampled interval.
  writer.write_series("tip", {0.0, 0.2, 0.3}, {1.0, 2.0, 3.0});
  const std::string xml = slurp(writer.xdmf_path());
  EXPECT_TRUE(tags_balanced(xml)) << xml;
  const auto tip = grid_values(xml, "tip");
  ASSERT_EQ(tip.size(), 3u);
  EXPECT_DOUBLE_EQ(tip[0], 1.0);
  EXPECT_DOUBLE_EQ(tip[1], 2.5);
  EXPECT_TRUE(std::isnan(tip[2])) << "0.5 s is after the last sample";
  const PointFrame second = make_frame(6, 0.25, 2, true);
  const auto& pressure = second.scalars.at("pressure");
  EXPECT_DOUBLE_EQ(grid_values(xml, "frame_pressure_max")[1],
                   *std::max_element(pressure.begin(), pressure.end()));
}
