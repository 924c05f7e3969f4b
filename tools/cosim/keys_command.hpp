// `cosim keys [participant]`: the scenario key reference, generated from the parameter
// declarations (visit_parameters beside each parameter struct, cosim/scenario/parameters.hpp).
// docs/scenario-keys.md is its output for all participants; a test keeps the two equal.
#pragma once

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

namespace cosim::tool {

// Participants with declared keys, in the order the reference lists them.
std::vector<std::string> keyed_participants();

// The reference as Markdown: one participant's section, or (empty name) the whole document.
std::string keys_markdown(const std::string& participant = "");

// The `keys` subcommand: prints keys_markdown(participant) when parsed.
inline void add_keys_command(CLI::App& app) {
  auto participant = std::make_shared<std::string>();
  auto* command = app.add_subcommand(
      "keys", "print the scenario keys (type, default, range, unit) of a participant, or all");
  command->add_option("participant", *participant, "participant name (default: all)")
      ->check(CLI::IsMember(keyed_participants()));
  command->callback([participant] { fmt::print("{}", keys_markdown(*participant)); });
}

}  // namespace cosim::tool
