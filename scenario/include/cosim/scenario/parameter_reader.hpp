// The scenario parser as a visitor of a parameter declaration (parameters.hpp): each declared key
// is read from a Section with its range, the struct's value as the default (written into the
// resolved scenario like every Section read), and each rule is reported at its key with file and
// line. A key that means nothing with the other values is refused as "only used with ...".
#pragma once

#include <unistd.h>

#include <cstdio>
#include <string>

#include "cosim/scenario/parameters.hpp"
#include "cosim/scenario/section.hpp"

namespace cosim::scenario {

class SectionReader {
 public:
  explicit SectionReader(Section& section) : section_(section) {}

  void operator()(const Key& key, double& value) {
    if (!usable(key)) return;
    const std::string name(key.name);
    value = key.required ? section_.number(name, key.range)
                         : section_.number(name, key.scenario_fallback.value_or(value), key.range);
  }
  void operator()(const Key& key, int& value) {
    if (!usable(key)) return;
    const std::string name(key.name);
    const int fallback = key.scenario_fallback ? static_cast<int>(*key.scenario_fallback) : value;
    value = key.required ? section_.integer(name, key.range)
                         : section_.integer(name, fallback, key.range);
  }
  // Seeds: read as a non-negative int (the scenario's integers are ints).
  void operator()(const Key& key, unsigned& value) {
    int as_int = static_cast<int>(value);
    (*this)(key, as_int);
    value = static_cast<unsigned>(as_int);
  }
  void operator()(const Key& key, bool& value) {
    if (!usable(key)) return;
    value = section_.flag(std::string(key.name),
                          key.scenario_fallback ? *key.scenario_fallback != 0.0 : value);
  }
  void operator()(const Key& key, Eigen::Vector3d& value) {
    if (!usable(key)) return;
    const std::string name(key.name);
    value = key.required ? section_.vector3(name) : section_.vector3(name, value);
  }
  void operator()(const Key& key, Eigen::Vector2d& value) {
    if (!usable(key)) return;
    const std::string name(key.name);
    value = key.required ? section_.vector2(name) : section_.vector2(name, value);
  }
  void operator()(const Key& key, std::vector<double>& values) {
    if (!usable(key)) return;
    const std::string name(key.name);
    values = key.required ? section_.numbers(name, key.range)
                          : section_.numbers(name, values, key.range);
  }
  void operator()(const Key& key, std::string& value) {
    if (!usable(key)) return;
    const std::string name(key.name);
    value = key.required ? section_.text(name) : section_.text(name, value);
  }
  // A file named relative to the bundle, which must exist (written absolute into the resolved
  // scenario); without a default an absent optional file stays empty.
  void operator()(const Key& key, std::filesystem::path& value) {
    if (!usable(key)) return;
    const std::string name(key.name);
    if (key.required || section_.has(name)) value = section_.existing_file(name);
  }
  template <class E, std::size_t N>
  void operator()(const Key& key, E& value, const Choices<E, N>& choices) {
    if (!usable(key)) return;
    std::vector<std::string> names;
    for (const auto& c : choices) names.emplace_back(c.name);
    const std::string name(key.name);
    const std::string chosen =
        key.required ? section_.text(name, names)
                     : section_.text(name, std::string(choice_name(choices, value)), names);
    for (const auto& c : choices)
      if (c.name == chosen) value = c.value;
  }
  void rule(std::string_view key, bool ok, std::string_view problem) {
    if (!ok) section_.fail(std::string(key), std::string(problem));
  }

 private:
  // false: skip the key (unused with the other values, or absent and omissible).
  bool usable(const Key& key) {
    const std::string name(key.name);
    if (!key.active) {
      if (section_.has(name)) section_.fail(name, "only used with " + std::string(key.condition));
      return false;
    }
    return !(key.omissible && !section_.has(name));
  }
  Section& section_;
};

// Reads every declared key of `parameters` from `section`.
template <class T>
void read_parameters(Section& section, T& parameters) {
  SectionReader reader(section);
  visit_parameters(parameters, reader);
}

// Runs `check` (a library's validation, throwing ParameterError) and reports what it refuses at
// the key in `section`, so `cosim validate` says file:line: key for the library's own rules.
template <class Check>
void check_at_keys(Section& section, Check&& check) {
  try {
    check();
  } catch (const ParameterError& error) {
    section.fail(error.key(), error.problem());
  }
}

// The machine's physical memory [bytes] (sysconf), 0 when unknown.
inline double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page_size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page_size > 0 ? static_cast<double>(pages) * static_cast<double>(page_size)
                                    : 0.0;
}

// "4.8 GB", "512 MB"
inline std::string format_bytes(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB"};
  int unit = 0;
  while (bytes >= 1000.0 && unit < 5) {
    bytes /= 1000.0;
    ++unit;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.3g %s", bytes, units[unit]);
  return text;
}

// A participant's memory estimated from its parameters, refused before anything starts when it
// exceeds the machine's physical memory (a plant field of 1e6 x 1e4 links used to validate and
// then die of std::bad_alloc).
class MemoryBudget {
 public:
  explicit MemoryBudget(std::string participant, double limit = physical_memory_bytes())
      : participant_(std::move(participant)), limit_(limit) {}
  // Adds what `key` of `section` asks for (`what`: how it was estimated) and refuses at that key
  // when the total exceeds the machine.
  void add(Section& section, const std::string& key, double bytes, const std::string& what) {
    total_ += bytes;
    if (limit_ > 0.0 && total_ > limit_) {
      section.fail(key, participant_ + " needs about " + format_bytes(total_) + " of memory (" +
                            what + "), more than this machine's " + format_bytes(limit_) +
                            " of physical memory");
    }
  }
  double total() const { return total_; }

 private:
  std::string participant_;
  double limit_;
  double total_ = 0.0;
};

}  // namespace cosim::scenario
