#include "cosim/scenario/section.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "cosim/scenario/document.hpp"

namespace cosim::scenario {
namespace {

// "file:line: key 'k': problem"; a key an override wrote (--set, --perturb, a sweep's --vary)
// has no line in the file (`line` 0, from yaml-cpp's null mark), and the error says so instead.
ScenarioError key_error(const std::filesystem::path& file, int line, const std::string& key,
                        const std::string& problem) {
  if (line <= 0) {
    return ScenarioError(
        fmt::format("{}: key '{}' (set on the command line): {}", file.string(), key, problem));
  }
  return ScenarioError(fmt::format("{}:{}: key '{}': {}", file.string(), line, key, problem));
}

}  // namespace

// The checks on the file itself (kind, size, duplicate keys) live in document.cpp.
YAML::Node load_yaml_file(const std::filesystem::path& file) {
  return load_document(file);
}

Section Section::root(const YAML::Node& node, const std::filesystem::path& file,
                      const YAML::Node& resolved) {
  auto source = std::make_shared<Source>();
  source->file = file;
  if (!node.IsMap()) {
    throw ScenarioError(fmt::format("{}:1: the scenario must be a mapping of keys", file.string()));
  }
  return Section(node, "", source, resolved);
}

Section::Section(YAML::Node node, std::string path, std::shared_ptr<Source> source,
                 YAML::Node resolved)
    : node_(std::move(node)),
      path_(std::move(path)),
      source_(std::move(source)),
      resolved_(std::move(resolved)),
      record_(std::make_shared<Record>(Record{node_, path_, {}})) {
  source_->records.push_back(record_);
}

std::string Section::dotted(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

int Section::line_of(const std::string& key) const {
  if (node_ && node_.IsMap()) {
    // The key's own line (a mapping value starts on the next line).
    for (const auto& item : node_) {
      if (item.first.Scalar() == key) return item.first.Mark().line + 1;
    }
  }
  if (node_) return node_.Mark().line + 1;
  return 1;
}

void Section::fail(const std::string& key, const std::string& problem) const {
  throw key_error(source_->file, line_of(key), dotted(key), problem);
}

bool Section::has(const std::string& key) const {
  return node_ && node_.IsMap() && node_[key] && !node_[key].IsNull();
}

std::vector<std::string> Section::keys() const {
  std::vector<std::string> result;
  if (!node_ || !node_.IsMap()) return result;
  for (const auto& item : node_) result.push_back(item.first.as<std::string>());
  return result;
}

YAML::Node Section::required(const std::string& key) const {
  mark_read(key);
  if (!has(key)) fail(key, "required key is missing");
  return node_[key];
}

double Section::to_number(const YAML::Node& value, const std::string& key) const {
  if (!value.IsScalar()) fail(key, "expected a number");
  try {
    const double number = value.as<double>();
    if (!std::isfinite(number)) fail(key, "expected a finite number, got '" + value.Scalar() + "'");
    return number;
  } catch (const YAML::Exception&) {
    fail(key, "expected a number, got '" + value.Scalar() + "'");
  }
}

void Section::check_range(const std::string& key, double value, const Range& range) const {
  if (!range.contains(value)) fail(key, out_of_range(value, range));
}

double Section::number(const std::string& key, double fallback, Range range) {
  mark_read(key);
  const double value = has(key) ? to_number(node_[key], key) : fallback;
  check_range(key, value, range);
  resolved_[key] = value;
  return value;
}

double Section::number(const std::string& key, Range range) {
  const double value = to_number(required(key), key);
  check_range(key, value, range);
  resolved_[key] = value;
  return value;
}

int Section::integer(const std::string& key, int fallback, Range range) {
  if (!has(key)) {
    mark_read(key);
    check_range(key, fallback, range);
    resolved_[key] = fallback;
    return fallback;
  }
  return integer(key, range);
}

int Section::integer(const std::string& key, Range range) {
  const YAML::Node value = required(key);
  int result = 0;
  try {
    if (!value.IsScalar()) throw YAML::Exception(value.Mark(), "");
    result = value.as<int>();
  } catch (const YAML::Exception&) {
    fail(key,
         "expected an integer, got '" + (value.IsScalar() ? value.Scalar() : "a collection") + "'");
  }
  check_range(key, result, range);
  resolved_[key] = result;
  return result;
}

bool Section::flag(const std::string& key, bool fallback) {
  mark_read(key);
  bool result = fallback;
  if (has(key)) {
    try {
      if (!node_[key].IsScalar()) throw YAML::Exception(node_[key].Mark(), "");
      result = node_[key].as<bool>();
    } catch (const YAML::Exception&) {
      fail(key, "expected true or false");
    }
  }
  resolved_[key] = result;
  return result;
}

std::string Section::text(const std::string& key, const std::string& fallback,
                          const std::vector<std::string>& allowed) {
  if (!has(key)) {
    mark_read(key);
    resolved_[key] = fallback;
    return fallback;
  }
  return text(key, allowed);
}

std::string Section::text(const std::string& key, const std::vector<std::string>& allowed) {
  const YAML::Node value = required(key);
  if (!value.IsScalar()) fail(key, "expected a text value");
  const std::string result = value.Scalar();
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), result) == allowed.end()) {
    fail(key, fmt::format("'{}' is not one of: {}", result, fmt::join(allowed, ", ")));
  }
  resolved_[key] = result;
  return result;
}

std::vector<double> Section::numbers(const std::string& key, Range range) {
  const YAML::Node value = required(key);
  if (!value.IsSequence()) fail(key, "expected a list of numbers");
  std::vector<double> result;
  for (const auto& item : value) {
    result.push_back(to_number(item, key));
    check_range(key, result.back(), range);
  }
  resolved_[key] = result;
  return result;
}

std::vector<double> Section::numbers(const std::string& key, const std::vector<double>& fallback,
                                     Range range) {
  if (has(key)) return numbers(key, range);
  mark_read(key);
  for (double value : fallback) check_range(key, value, range);
  resolved_[key] = fallback;
  return fallback;
}

Eigen::Vector2d Section::vector2(const std::string& key) {
  const std::vector<double> values = numbers(key);
  if (values.size() != 2) fail(key, fmt::format("expected 2 numbers, got {}", values.size()));
  return {values[0], values[1]};
}

Eigen::Vector2d Section::vector2(const std::string& key, const Eigen::Vector2d& fallback) {
  if (has(key)) return vector2(key);
  mark_read(key);
  resolved_[key] = std::vector<double>{fallback.x(), fallback.y()};
  return fallback;
}

Eigen::Vector3d Section::vector3(const std::string& key) {
  const std::vector<double> values = numbers(key);
  if (values.size() != 3)
    fail(key, fmt::format("expected 3 numbers [x, y, z], got {}", values.size()));
  return {values[0], values[1], values[2]};
}

Eigen::Vector3d Section::vector3(const std::string& key, const Eigen::Vector3d& fallback) {
  if (has(key)) return vector3(key);
  mark_read(key);
  resolved_[key] = std::vector<double>{fallback.x(), fallback.y(), fallback.z()};
  return fallback;
}

std::filesystem::path Section::existing_file(const std::string& key) {
  const std::string name = text(key);
  std::filesystem::path file = name;
  if (file.is_relative()) file = bundle_dir() / file;
  if (!std::filesystem::exists(file)) fail(key, "file not found: " + file.string());
  // The resolved scenario lives in the run folder, so it names files by absolute path.
  resolved_[key] = std::filesystem::absolute(file).lexically_normal().string();
  return file;
}

Section Section::child(const std::string& key) {
  const YAML::Node value = required(key);
  if (!value.IsMap()) fail(key, "expected a mapping of keys");
  return Section(value, dotted(key), source_, resolved_[key]);
}

Section Section::optional_child(const std::string& key) {
  mark_read(key);
  if (!has(key))
    return Section(YAML::Node(YAML::NodeType::Map), dotted(key), source_, resolved_[key]);
  return child(key);
}

std::vector<Section> Section::list(const std::string& key) {
  const YAML::Node value = required(key);
  if (!value.IsSequence()) fail(key, "expected a list");
  std::vector<Section> result;
  YAML::Node resolved_list = resolved_[key];
  for (std::size_t index = 0; index < value.size(); ++index) {
    if (!value[index].IsMap()) {
      throw key_error(source_->file, value[index].Mark().line + 1,
                      fmt::format("{}[{}]", dotted(key), index), "expected a mapping of keys");
    }
    YAML::Node resolved_item(YAML::NodeType::Map);
    resolved_list.push_back(resolved_item);
    result.push_back(Section(value[index], fmt::format("{}[{}]", dotted(key), index), source_,
                             resolved_list[index]));
  }
  return result;
}

void Section::finish() const {
  for (const auto& record : source_->records) {
    if (!record->path.starts_with(path_)) continue;
    if (!record->node || !record->node.IsMap()) continue;
    for (const auto& item : record->node) {
      const std::string key = item.first.as<std::string>();
      if (!record->read_keys.contains(key)) {
        const std::string where = record->path.empty() ? key : record->path + "." + key;
        throw key_error(source_->file, item.first.Mark().line + 1, where, "unknown key");
      }
    }
  }
}

}  // namespace cosim::scenario
