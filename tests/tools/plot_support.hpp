// Whether this machine can draw figures: the same interpreters `cosim` tries.
#pragma once

#include <cstdlib>
#include <string>

namespace cosim::testing {

inline bool matplotlib_available() {
  return std::system("python3 -c 'import matplotlib' >/dev/null 2>&1") == 0 ||
         std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0;
}

// A python3 without its site packages, so without matplotlib.
inline constexpr const char* kPythonWithoutMatplotlib =
    "#!/bin/sh\nexec /usr/bin/python3 -S \"$@\"\n";

}  // namespace cosim::testing
