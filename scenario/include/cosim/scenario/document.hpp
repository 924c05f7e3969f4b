// Reading a scenario file from disk, before any key is interpreted: only a regular file of
// reasonable size is opened (a FIFO or device would block or never end), YAML syntax errors
// name the line, and a key written twice in one mapping is an error (yaml-cpp keeps both
// entries, and which one a reader sees depends on how it looks the key up).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>

namespace cosim::scenario {

// Scenario files are hand-written text; anything larger is a mistake (a data file named by
// accident) that would otherwise take minutes and gigabytes to parse.
inline constexpr std::uintmax_t kMaxScenarioBytes = 16u * 1024u * 1024u;

// Loads `file` as YAML. Throws ScenarioError naming the file (and the line and dotted key for
// a duplicate) when it is missing, not a regular file, larger than `max_bytes`, unreadable, not
// valid YAML, or has a duplicate key.
YAML::Node load_document(const std::filesystem::path& file,
                         std::uintmax_t max_bytes = kMaxScenarioBytes);

// Throws for the first key that appears twice in one mapping, at any depth (list items
// included): "file:line: key 'a.b': appears twice (first at line N)".
void check_duplicate_keys(const YAML::Node& document, const std::filesystem::path& file);

}  // namespace cosim::scenario
