// Small text files of a run (XDMF index, summary, resolved scenario) written so that a failure
// is never silent and never leaves a half-written file behind.
#pragma once

#include <filesystem>
#include <string>

namespace cosim::output {

// Writes `content` to a sibling temporary file (`<path>.tmp`) and renames it over `path`, so a
// reader, or a run killed halfway, never sees a half-written file. Any failure (disk full, no
// permission) throws std::runtime_error naming the file and the cause as strerror gives it,
// e.g. "cannot write '/run/summary.json': No space left on device", after removing the
// temporary file; `path` then keeps its previous content.
void write_file_atomically(const std::filesystem::path& path, const std::string& content);

}  // namespace cosim::output
