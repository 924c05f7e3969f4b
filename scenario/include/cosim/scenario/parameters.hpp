// Parameters declared once (project issue 14). A parameter struct comes with one function,
//
//   template <class P, class V> requires std::same_as<std::remove_const_t<P>, Struct>
//   void visit_parameters(P& p, V& v) {
//     v(Key("courant").in(Range{0.0, 1.0, true}).doc("Courant number of the step limit"),
//       p.courant);
//     v.rule("orifice_height", p.orifice_height < p.weir_height, "must be below the crest");
//   }
//
// that names every field once with its key, range, unit and a one-line description, and states
// the rules between fields. Each job is a visitor of that one list (the idea of Drake's
// Serialize(Archive*) with DRAKE_NVP): the scenario parser (SectionReader, parameter_reader.hpp)
// reads the keys from a Section, ParameterCheck below is the library's own check of the struct,
// and KeyTable writes the key reference (`cosim keys`, docs/scenario-keys.md). So `cosim
// validate` and the library refuse the same values with the same words.
//
// Header-only and free of YAML: the physics libraries include it.
#pragma once

#include <Eigen/Core>
#include <array>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace cosim::scenario {

// A number printed as fmt's "{}" prints it (shortest round trip; fixed from 1e-4 to below
// 1e16, else scientific), so messages read the same from the parser and the libraries.
inline std::string format_number(double value) {
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  if (std::isnan(value)) return "nan";
  std::array<char, 64> buffer{};
  auto written = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value,
                               std::chars_format::scientific);
  const std::string scientific(buffer.data(), written.ptr);
  const int exponent = std::stoi(scientific.substr(scientific.find('e') + 1));
  if (exponent < -4 || exponent >= 16) return scientific;
  written =
      std::to_chars(buffer.data(), buffer.data() + buffer.size(), value, std::chars_format::fixed);
  return std::string(buffer.data(), written.ptr);
}

struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  bool max_exclusive = false;
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true}; }
  static Range non_negative() { return {0.0}; }
  static Range between(double low, double high) { return {low, high}; }
  static Range fraction() { return {0.0, 1.0}; }
  // [low, high): e.g. a threshold that must stay below 1.
  static Range below(double low, double high) { return {low, high, false, true}; }
  bool contains(double value) const {
    const bool low = min_exclusive ? value > min : value >= min;
    const bool high = max_exclusive ? value < max : value <= max;
    return low && high;
  }
  bool unbounded() const { return std::isinf(min) && std::isinf(max); }
  // "(0, 1]", "[0.5, 1)", "[0, inf]"
  std::string text() const {
    std::string out = min_exclusive ? "(" : "[";  // appended: GCC 12 -Wrestrict misfires on +
    out.append(format_number(min)).append(", ").append(format_number(max));
    out.append(max_exclusive ? ")" : "]");
    return out;
  }
};

// The problem of a value outside its range, in the words of every scenario error.
inline std::string out_of_range(double value, const Range& range) {
  return "value " + format_number(value) + " is out of range " + range.text();
}

// One parameter's declaration. Built in the visit function by chaining:
//   Key("voidage_radius").unit("m").in(Range::positive()).needed()
//       .only_with(p.voidage_correction, "voidage_correction: true").doc("...")
struct Key {
  std::string_view name;
  std::string_view unit_text;
  std::string_view description;
  Range range;
  bool required = false;       // no default: a scenario must give it
  bool omissible = false;      // absent: the library value stands and nothing is written
  bool active = true;          // false: the key means nothing with the other values (only_with)
  std::string_view condition;  // when it is used, e.g. "drag_law: seed004"
  std::optional<double> scenario_fallback;  // a scenario default other than the struct's
  std::string_view default_text;            // the default as the key table shows it

  explicit Key(std::string_view key) : name(key) {}
  Key unit(std::string_view text) const {
    return with([&](Key& k) { k.unit_text = text; });
  }
  Key doc(std::string_view text) const {
    return with([&](Key& k) { k.description = text; });
  }
  Key in(Range r) const {
    return with([&](Key& k) { k.range = r; });
  }
  Key needed() const {
    return with([](Key& k) { k.required = true; });
  }
  // Absent means "not set" (default_text says what that does).
  Key omitted_means(std::string_view text) const {
    return with([&](Key& k) {
      k.omissible = true;
      k.default_text = text;
    });
  }
  Key only_with(bool used, std::string_view when) const {
    return with([&](Key& k) {
      k.active = used;
      k.condition = when;
    });
  }
  // How the key table shows a default that the reader sets from other values first.
  Key shown_default(std::string_view text) const {
    return with([&](Key& k) { k.default_text = text; });
  }
  // The default of a scenario when it differs from the struct's own (text: how the table
  // shows it, empty for the number itself).
  Key scenario_default(double value, std::string_view text = {}) const {
    return with([&](Key& k) {
      k.scenario_fallback = value;
      k.default_text = text;
    });
  }

 private:
  template <class F>
  Key with(F change) const {
    Key copy = *this;
    change(copy);
    return copy;
  }
};

// The names of an enum's values as a scenario spells them.
template <class E>
struct Choice {
  std::string_view name;
  E value;
};
template <class E, std::size_t N>
using Choices = std::array<Choice<E>, N>;

template <class E, std::size_t N>
std::string_view choice_name(const Choices<E, N>& choices, E value) {
  for (const auto& c : choices)
    if (c.value == value) return c.name;
  return "?";
}

// A parameter the library refuses: the key (relative to the struct) and the problem, so a
// parser can report it at the key's file and line. what(): "Owner: key 'k': problem".
class ParameterError : public std::invalid_argument {
 public:
  ParameterError(const std::string& owner, std::string key, std::string problem)
      : std::invalid_argument(owner + ": key '" + key + "': " + problem),
        key_(std::move(key)),
        problem_(std::move(problem)) {}
  const std::string& key() const { return key_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string key_;
  std::string problem_;
};

// The library's check of a struct: every declared value in its range, every rule kept.
class ParameterCheck {
 public:
  explicit ParameterCheck(std::string owner) : owner_(std::move(owner)) {}
  void operator()(const Key& key, const double& value) const { check(key, value); }
  void operator()(const Key& key, const int& value) const { check(key, value); }
  void operator()(const Key& key, const unsigned& value) const { check(key, value); }
  void operator()(const Key&, const bool&) const {}
  void operator()(const Key& key, const Eigen::Vector3d& value) const {
    if (key.active && !value.allFinite()) fail(key.name, "expected finite numbers");
  }
  void operator()(const Key& key, const Eigen::Vector2d& value) const {
    if (key.active && !value.allFinite()) fail(key.name, "expected finite numbers");
  }
  void operator()(const Key& key, const std::vector<double>& values) const {
    for (double value : values) check(key, value);
  }
  // Texts and files: the parser checks a file exists; the library opens it and says what is wrong.
  void operator()(const Key&, const std::string&) const {}
  void operator()(const Key&, const std::filesystem::path&) const {}
  template <class E, std::size_t N>
  void operator()(const Key& key, const E& value, const Choices<E, N>& choices) const {
    if (key.active && choice_name(choices, value) == "?") fail(key.name, "not a known choice");
  }
  void rule(std::string_view key, bool ok, std::string_view problem) const {
    if (!ok) fail(key, problem);
  }
  [[noreturn]] void fail(std::string_view key, std::string_view problem) const {
    throw ParameterError(owner_, std::string(key), std::string(problem));
  }

 private:
  void check(const Key& key, double value) const {
    if (!key.active) return;  // unused with the other values: the library ignores it
    if (std::isnan(value) || !key.range.contains(value))
      fail(key.name, out_of_range(value, key.range));
  }
  std::string owner_;
};

// Throws ParameterError (a std::invalid_argument) naming the key of the first value out of
// range or rule broken; `owner` starts the message ("MpsParameters").
template <class T>
void check_parameters(const T& parameters, const std::string& owner) {
  ParameterCheck check(owner);
  visit_parameters(parameters, check);
}

// The key reference: one row per key, in declaration order.
struct KeyRow {
  std::string key, type, default_value, range, unit, description;
};

class KeyTable {
 public:
  // prefix: dotted path of the struct inside the participant's section ("materials.debris.").
  explicit KeyTable(std::string prefix = {}) : prefix_(std::move(prefix)) {}
  void operator()(const Key& key, const double& value) { add(key, "number", number(key, value)); }
  void operator()(const Key& key, const int& value) { add(key, "integer", number(key, value)); }
  void operator()(const Key& key, const unsigned& value) {
    add(key, "integer", number(key, value));
  }
  void operator()(const Key& key, const bool& value) {
    const bool shown = key.scenario_fallback ? *key.scenario_fallback != 0.0 : value;
    add(key, "flag", fallback(key, shown ? "true" : "false"), "true, false");
  }
  void operator()(const Key& key, const Eigen::Vector3d& value) {
    add(key, "[x, y, z]",
        fallback(key, "[" + format_number(value.x()) + ", " + format_number(value.y()) + ", " +
                          format_number(value.z()) + "]"),
        "");
  }
  void operator()(const Key& key, const Eigen::Vector2d& value) {
    add(key, "[a, b]",
        fallback(key, "[" + format_number(value.x()) + ", " + format_number(value.y()) + "]"), "");
  }
  // Each number of the list in the key's range.
  void operator()(const Key& key, const std::vector<double>& values) {
    std::string shown;
    for (double value : values) shown += (shown.empty() ? "" : ", ") + format_number(value);
    add(key, "list of numbers", fallback(key, "[" + shown + "]"));
  }
  void operator()(const Key& key, const std::string& value) {
    add(key, "text", fallback(key, value), "");
  }
  void operator()(const Key& key, const std::filesystem::path& value) {
    add(key, "file", fallback(key, value.string()), "relative to the bundle");
  }
  template <class E, std::size_t N>
  void operator()(const Key& key, const E& value, const Choices<E, N>& choices) {
    std::string names;
    for (const auto& c : choices) names += (names.empty() ? "" : ", ") + std::string(c.name);
    add(key, "choice", fallback(key, std::string(choice_name(choices, value))), names);
  }
  void rule(std::string_view key, bool, std::string_view problem) {
    rules_.push_back(prefix_ + std::string(key) + ": " + std::string(problem));
  }
  void set_prefix(std::string prefix) { prefix_ = std::move(prefix); }
  const std::vector<KeyRow>& rows() const { return rows_; }
  const std::vector<std::string>& rules() const { return rules_; }

 private:
  std::string fallback(const Key& key, std::string shown) const {
    if (key.required) return "required";
    if (!key.default_text.empty()) return std::string(key.default_text);
    return shown;
  }
  std::string number(const Key& key, double value) const {
    return fallback(key, format_number(key.scenario_fallback.value_or(value)));
  }
  void add(const Key& key, std::string type, std::string shown,
           std::optional<std::string> range = std::nullopt) {
    std::string description(key.description);
    if (!key.condition.empty()) description += " (only with " + std::string(key.condition) + ")";
    rows_.push_back({prefix_ + std::string(key.name), std::move(type), std::move(shown),
                     range ? *range : (key.range.unbounded() ? "" : key.range.text()),
                     std::string(key.unit_text), std::move(description)});
  }
  std::string prefix_;
  std::vector<KeyRow> rows_;
  std::vector<std::string> rules_;
};

// The rows of a default-constructed struct (its library defaults) under `prefix`.
template <class T>
void describe_parameters(KeyTable& table, const T& defaults = T{}) {
  visit_parameters(defaults, table);
}

}  // namespace cosim::scenario
