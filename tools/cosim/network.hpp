// Where a run's LCM traffic goes. LCM needs a multicast route; machines without one (containers,
// CI) get a private network namespace with loopback multicast, made without root.
#pragma once

#include <string>

namespace cosim::tool {

// True when LCM can open a multicast URL here.
bool multicast_available();

// Re-executes this program inside `unshare -rn` with loopback up and a multicast route on it.
// Returns only on failure (with the reason).
std::string reexec_in_private_network(int argc, char** argv);

// Set in the environment of the re-executed program.
inline constexpr const char* kPrivateNetworkVariable = "COSIM_PRIVATE_NETWORK";

}  // namespace cosim::tool
