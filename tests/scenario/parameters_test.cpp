// One declaration per parameter (parameters.hpp): the scenario parser (SectionReader), the
// library check (ParameterCheck) and the key table (KeyTable) all visit it, so they agree on
// ranges, defaults and words.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <concepts>
#include <fstream>

#include "cosim/scenario/parameter_reader.hpp"

namespace demo {

enum class Mode { fast, exact };
inline constexpr cosim::scenario::Choices<Mode, 2> kModes{
    {{"fast", Mode::fast}, {"exact", Mode::exact}}};

struct Settings {
  double threshold = 0.97;
  int layers = 2;
  bool extra = false;
  double extra_size = 0.0;
  Mode mode = Mode::fast;
  double top = 1.0, bottom = 0.0;
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, Settings>
void visit_parameters(P& p, V& v) {
  using cosim::scenario::Key;
  using cosim::scenario::Range;
  v(Key("threshold").in(Range::below(0.5, 1.0)).doc("beta"), p.threshold);
  v(Key("layers").in(Range::between(1, 10)).unit("").doc("wall layers"), p.layers);
  v(Key("extra").doc("an extra part"), p.extra);
  v(Key("extra_size").unit("m").in(Range::positive()).needed().only_with(p.extra, "extra: true"),
    p.extra_size);
  v(Key("mode").doc("how"), p.mode, kModes);
  v(Key("bottom").unit("m"), p.bottom);
  v(Key("top").unit("m").scenario_default(2.0), p.top);
  v.rule("top", p.top > p.bottom, "must be above bottom");
}

// Texts, files, lists of numbers and pairs (the fluid's sensors and partitions).
struct Sensor {
  std::string column;
  std::filesystem::path file;
  std::vector<double> depths{0.1};
  Eigen::Vector2d at = Eigen::Vector2d::Zero();
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, Sensor>
void visit_parameters(P& p, V& v) {
  using cosim::scenario::Key;
  using cosim::scenario::Range;
  v(Key("column").needed().doc("of the record"), p.column);
  v(Key("file").doc("the record"), p.file);
  v(Key("depths").unit("m").in(Range::positive()).doc("below the surface"), p.depths);
  v(Key("at").unit("m").needed().doc("[x, y]"), p.at);
}

}  // namespace demo

namespace cosim::scenario {
namespace {

struct Parsed {
  demo::Settings settings;
  YAML::Node resolved;
};

std::filesystem::path write_file(const std::string& text) {
  const auto file = std::filesystem::temp_directory_path() / "cosim-parameters-test.yaml";
  std::ofstream(file) << text;
  return file;
}

Parsed parse(const std::string& text) {
  Parsed out;
  out.resolved = YAML::Node(YAML::NodeType::Map);
  const auto file = write_file(text);
  Section root = Section::root(YAML::LoadFile(file.string()), file, out.resolved);
  Section section = root.child("demo");
  read_parameters(section, out.settings);
  check_at_keys(section, [&] { check_parameters(out.settings, "Settings"); });
  root.finish();
  return out;
}

std::string parse_error(const std::string& text) {
  try {
    parse(text);
  } catch (const ScenarioError& error) {
    return error.what();
  }
  return "";
}

std::string check_error(const demo::Settings& settings) {
  try {
    check_parameters(settings, "Settings");
  } catch (const ParameterError& error) {
    return error.what();
  }
  return "";
}

TEST(Parameters, NumbersPrintAsFmtPrintsThem) {
  for (double value : {0.0, 1.0, 0.5, 1000.0, 1e7, 1e-3, 1e-4, 1e-5, 1e-8, 0.45e-9, 1e15, 1e16,
                       -1.5, 123456.7, 0.97, 2.1, 1e300, 4.9e-324}) {
    EXPECT_EQ(format_number(value), fmt::format("{}", value)) << value;
  }
  EXPECT_EQ(format_number(std::numeric_limits<double>::infinity()), "inf");
}

TEST(Parameters, RangesIncludeOrExcludeEachBound) {
  EXPECT_EQ(Range::below(0.5, 1.0).text(), "[0.5, 1)");
  EXPECT_TRUE(Range::below(0.5, 1.0).contains(0.5));
  EXPECT_FALSE(Range::below(0.5, 1.0).contains(1.0));
  EXPECT_EQ((Range{0.0, 1.0, true}).text(), "(0, 1]");
  EXPECT_FALSE(Range::positive().contains(0.0));
}

TEST(Parameters, TheParserReadsDefaultsAndWritesThemResolved) {
  const Parsed parsed = parse("demo:\n  layers: 3\n");
  EXPECT_EQ(parsed.settings.layers, 3);
  EXPECT_DOUBLE_EQ(parsed.settings.threshold, 0.97);
  EXPECT_DOUBLE_EQ(parsed.settings.top, 2.0);  // the scenario default, not the struct's
  EXPECT_DOUBLE_EQ(parsed.resolved["demo"]["threshold"].as<double>(), 0.97);
  EXPECT_EQ(parsed.resolved["demo"]["mode"].as<std::string>(), "fast");
  EXPECT_DOUBLE_EQ(parsed.resolved["demo"]["top"].as<double>(), 2.0);
  EXPECT_FALSE(parsed.resolved["demo"]["extra_size"]) << "an unused key is not written";
}

// The parser and the library refuse the same value with the same words; the parser adds the
// file, line and dotted key.
TEST(Parameters, ParserAndLibraryRefuseTheSameValueInTheSameWords) {
  const std::string parsed = parse_error("demo:\n  layers: 3\n  threshold: 1.0\n");
  EXPECT_NE(parsed.find("cosim-parameters-test.yaml:3: key 'demo.threshold': value 1 is out of "
                        "range [0.5, 1)"),
            std::string::npos)
      << parsed;
  demo::Settings settings;
  settings.threshold = 1.0;
  EXPECT_EQ(check_error(settings), "Settings: key 'threshold': value 1 is out of range [0.5, 1)");
  settings.threshold = 0.9;
  settings.layers = 0;
  EXPECT_EQ(check_error(settings), "Settings: key 'layers': value 0 is out of range [1, 10]");
}

TEST(Parameters, ConditionalKeysAndRulesAreReportedAtTheirKey) {
  EXPECT_NE(parse_error("demo:\n  extra_size: 0.1\n")
                .find(":2: key 'demo.extra_size': only used with extra: true"),
            std::string::npos);
  EXPECT_NE(parse_error("demo:\n  extra: true\n").find("key 'demo.extra_size': required"),
            std::string::npos);
  EXPECT_DOUBLE_EQ(parse("demo:\n  extra: true\n  extra_size: 0.2\n").settings.extra_size, 0.2);
  EXPECT_NE(parse_error("demo:\n  bottom: 0\n  top: -1\n")
                .find(":3: key 'demo.top': must be above bottom"),
            std::string::npos);
  EXPECT_NE(parse_error("demo:\n  mode: slow\n").find("'slow' is not one of: fast, exact"),
            std::string::npos);
  demo::Settings settings;
  settings.top = -1.0;
  EXPECT_EQ(check_error(settings), "Settings: key 'top': must be above bottom");
  settings.top = 1.0;
  settings.extra = true;  // extra_size 0 is now used, and out of its range
  EXPECT_EQ(check_error(settings), "Settings: key 'extra_size': value 0 is out of range (0, inf]");
}

TEST(Parameters, TheKeyTableListsEveryKeyOnce) {
  KeyTable table("demo.");
  describe_parameters<demo::Settings>(table);
  ASSERT_EQ(table.rows().size(), 7u);
  EXPECT_EQ(table.rows()[0].key, "demo.threshold");
  EXPECT_EQ(table.rows()[0].default_value, "0.97");
  EXPECT_EQ(table.rows()[0].range, "[0.5, 1)");
  EXPECT_EQ(table.rows()[3].default_value, "required");
  EXPECT_NE(table.rows()[3].description.find("only with extra: true"), std::string::npos);
  EXPECT_EQ(table.rows()[4].range, "fast, exact");
  EXPECT_EQ(table.rows()[6].default_value, "2");
  ASSERT_EQ(table.rules().size(), 1u);
  EXPECT_EQ(table.rules()[0], "demo.top: must be above bottom");
}

TEST(Parameters, TextsFilesListsAndPairsAreReadCheckedAndListed) {
  const auto folder = std::filesystem::temp_directory_path();
  std::ofstream(folder / "cosim-parameters-record.csv") << "t\n";
  auto read = [&](const std::string& text) {
    YAML::Node resolved(YAML::NodeType::Map);
    const auto file = write_file(text);
    Section root = Section::root(YAML::LoadFile(file.string()), file, resolved);
    Section section = root.child("demo");
    demo::Sensor sensor;
    read_parameters(section, sensor);
    root.finish();
    return std::pair{sensor, resolved};
  };
  const auto [sensor, resolved] =
      read("demo:\n  column: P1\n  file: cosim-parameters-record.csv\n  at: [0.5, 0.25]\n");
  EXPECT_EQ(sensor.column, "P1");
  EXPECT_EQ(sensor.file, folder / "cosim-parameters-record.csv");
  EXPECT_EQ(sensor.at, Eigen::Vector2d(0.5, 0.25));
  ASSERT_EQ(sensor.depths.size(), 1u);
  EXPECT_EQ(resolved["demo"]["depths"][0].as<double>(), 0.1) << "the default is written";
  auto error = [&](const std::string& text) {
    try {
      read(text);
    } catch (const ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("demo:\n  column: P1\n  at: [1, 2, 3]\n")
                .find(":3: key 'demo.at': expected 2 numbers, got 3"),
            std::string::npos);
  EXPECT_NE(error("demo:\n  column: P1\n  at: [1, 2]\n  depths: [0.1, 0]\n")
                .find(":4: key 'demo.depths': value 0 is out of range (0, inf]"),
            std::string::npos);
  EXPECT_NE(error("demo:\n  column: P1\n  at: [1, 2]\n  file: nowhere.csv\n")
                .find(":4: key 'demo.file': file not found"),
            std::string::npos);
  EXPECT_NE(error("demo:\n  at: [1, 2]\n").find("key 'demo.column': required key is missing"),
            std::string::npos);
  demo::Sensor bad;
  bad.depths = {0.2, -1.0};
  EXPECT_THROW(check_parameters(bad, "Sensor"), ParameterError);
  KeyTable table;
  describe_parameters<demo::Sensor>(table);
  ASSERT_EQ(table.rows().size(), 4u);
  EXPECT_EQ(table.rows()[0].type, "text");
  EXPECT_EQ(table.rows()[1].type, "file");
  EXPECT_EQ(table.rows()[2].type, "list of numbers");
  EXPECT_EQ(table.rows()[2].default_value, "[0.1]");
  EXPECT_EQ(table.rows()[2].range, "(0, inf]");
  EXPECT_EQ(table.rows()[3].type, "[a, b]");
  EXPECT_EQ(table.rows()[3].default_value, "required");
}

TEST(Parameters, AMemoryEstimateAboveTheMachineIsRefusedAtItsKey) {
  YAML::Node resolved(YAML::NodeType::Map);
  const auto file = write_file("demo:\n  count: 1000000\n");
  Section root = Section::root(YAML::LoadFile(file.string()), file, resolved);
  Section section = root.child("demo");
  EXPECT_GT(physical_memory_bytes(), 1e8);
  MemoryBudget budget("demo", 16e9);
  budget.add(section, "count", 8e9, "half");
  try {
    budget.add(section, "count", 9e9, "1e6 things x 9 kB");
    FAIL() << "17 GB on a 16 GB machine must be refused";
  } catch (const ScenarioError& error) {
    EXPECT_EQ(std::string(error.what()),
              file.string() +
                  ":2: key 'demo.count': demo needs about 17 GB of memory (1e6 things x 9 kB), "
                  "more than this machine's 16 GB of physical memory");
  }
}

}  // namespace
}  // namespace cosim::scenario
