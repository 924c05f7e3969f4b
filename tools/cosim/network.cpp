#include "network.hpp"

#include <stdlib.h>
#include <unistd.h>
#include <lcm/lcm-cpp.hpp>

#include <cerrno>
#include <cstring>
#include <vector>

#include "cosim/coupler/bus.hpp"

namespace cosim::tool {

bool multicast_available() {
  // A throwaway URL of its own, so the probe hears nobody.
  lcm::LCM probe(coupler::run_lcm_url(static_cast<int64_t>(getpid()) * 7919 + 1));
  return probe.good();
}

std::string reexec_in_private_network(int argc, char** argv) {
  setenv(kPrivateNetworkVariable, "1", 1);
  std::vector<std::string> words{"unshare",
                                 "-rn",
                                 "sh",
                                 "-c",
                                 "ip link set lo up && ip route add 224.0.0.0/4 dev lo && "
                                 "exec \"$0\" \"$@\"",
                                 "/proc/self/exe"};
  // /proc/self/exe would name `sh` after exec: pass our real path instead.
  char self[4096];
  const ssize_t length = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (length > 0) {
    self[length] = '\0';
    words.back() = self;
  }
  for (int i = 1; i < argc; ++i) words.emplace_back(argv[i]);
  std::vector<char*> arguments;
  for (auto& word : words) arguments.push_back(word.data());
  arguments.push_back(nullptr);
  execvp("unshare", arguments.data());
  return std::string("cannot start `unshare -rn`: ") + std::strerror(errno);
}

}  // namespace cosim::tool
