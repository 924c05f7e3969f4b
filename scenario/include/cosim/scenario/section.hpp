// Checked access to one mapping of a scenario file. Every read names the file, line and the
// dotted key on error; keys never read are reported as unknown by finish(); every value used,
// defaults included, is written into the resolved scenario saved with the run.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "cosim/scenario/parameters.hpp"  // Range

namespace cosim::scenario {

class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Section {
 public:
  // The root mapping of a file. bundle_dir resolves relative file names.
  static Section root(const YAML::Node& node, const std::filesystem::path& file,
                      const YAML::Node& resolved);

  bool has(const std::string& key) const;
  const std::string& path() const { return path_; }
  const std::filesystem::path& file() const { return source_->file; }
  std::filesystem::path bundle_dir() const { return source_->file.parent_path(); }

  double number(const std::string& key, double fallback, Range range = {});
  double number(const std::string& key, Range range = {});  // required
  int integer(const std::string& key, int fallback, Range range = {});
  int integer(const std::string& key, Range range = {});
  bool flag(const std::string& key, bool fallback);
  std::string text(const std::string& key, const std::string& fallback,
                   const std::vector<std::string>& allowed = {});
  std::string text(const std::string& key, const std::vector<std::string>& allowed = {});
  // A required text that must be one of `allowed`.
  std::string choice(const std::string& key, const std::vector<std::string>& allowed) {
    return text(key, allowed);
  }
  Eigen::Vector3d vector3(const std::string& key, const Eigen::Vector3d& fallback);
  Eigen::Vector3d vector3(const std::string& key);
  Eigen::Vector2d vector2(const std::string& key, const Eigen::Vector2d& fallback);
  Eigen::Vector2d vector2(const std::string& key);
  std::vector<double> numbers(const std::string& key, const std::vector<double>& fallback,
                              Range range);
  std::vector<double> numbers(const std::string& key, Range range = {});
  // A file named relative to the bundle folder; it must exist.
  std::filesystem::path existing_file(const std::string& key);

  // Sub-mappings. optional_child returns an empty section when the key is absent.
  Section child(const std::string& key);
  Section optional_child(const std::string& key);
  std::vector<Section> list(const std::string& key);
  std::vector<std::string> keys() const;

  // Throws for the first key, in this section or any section reached from it, present in the
  // file but never read.
  void finish() const;

  // An error message in the standard form, for checks a caller does itself.
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;
  int line_of(const std::string& key) const;

 private:
  struct Record {
    YAML::Node node;
    std::string path;
    std::set<std::string> read_keys;
  };
  struct Source {
    std::filesystem::path file;
    std::vector<std::shared_ptr<Record>> records;
  };
  Section(YAML::Node node, std::string path, std::shared_ptr<Source> source, YAML::Node resolved);
  void mark_read(const std::string& key) const { record_->read_keys.insert(key); }
  YAML::Node required(const std::string& key) const;
  std::string dotted(const std::string& key) const;
  double to_number(const YAML::Node& node, const std::string& key) const;
  void check_range(const std::string& key, double value, const Range& range) const;

  YAML::Node node_;
  std::string path_;
  std::shared_ptr<Source> source_;
  YAML::Node resolved_;
  std::shared_ptr<Record> record_;
};

// Loads a YAML file, turning parse errors into ScenarioError with file and line.
YAML::Node load_yaml_file(const std::filesystem::path& file);

}  // namespace cosim::scenario
