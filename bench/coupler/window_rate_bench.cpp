// Coupling overhead: windows per second of a flow and a solid exchanging N-point fields through
// the real coupler, bus and links (all in one process, on the run's multicast URL), for several
// N and both schemes. Prints the figures; the physics costs nothing here, so this is the floor a
// coupled scene pays per window.
#include <fmt/format.h>

#include <chrono>
#include <thread>

#include "cosim/coupler/coupler.hpp"
#include "cosim/coupler/frame.hpp"
#include "cosim/coupler/links.hpp"

namespace {

using namespace cosim;

scenario::Scene make_scene(int windows, const std::string& scheme) {
  scenario::Scene scene;
  scene.name = "window_rate";
  scene.duration = windows * 1e-3;
  scene.coupling.window = 1e-3;
  scene.coupling.scheme = scheme;
  scene.coupling.timeout = 10.0;
  scene.participants = {
      {"prescribed_flow", "prescribed_flow", "prescribed_flow", scenario::Role::flow},
      {"vegetation_beam", "vegetation_beam", "vegetation_beam", scenario::Role::solid}};
  return scene;
}

coupler::ParticipantOptions options(const std::string& name, const std::string& url,
                                    int64_t run_id) {
  coupler::ParticipantOptions participant;
  participant.name = name;
  participant.url = url;
  participant.run_id = run_id;
  participant.timeout = 10.0;
  return participant;
}

// The coupler refuses a participant that declares no world frame.
void declare_world(coupler::Participant& participant) {
  participant.declare(coupler::FrameDeclaration{}.to_json());
}

void run_flow(const scenario::Scene& scene, const std::string& url, int64_t run_id) {
  coupler::Participant participant(options("prescribed_flow", url, run_id));
  declare_world(participant);
  coupler::FlowLink link(participant, scene);
  while (true) {
    const auto window = participant.next_window();
    if (window.finish) {
      participant.finished("{}");
      return;
    }
    for (const auto& solid : link.receive_solids(window)) {
      const std::vector<double> water(solid.positions.size(), 1.0);
      link.publish_samples(solid.name, solid.velocities, water);
    }
    participant.done(1);
  }
}

void run_solid(const scenario::Scene& scene, const std::string& url, int64_t run_id, int points) {
  coupler::Participant participant(options("vegetation_beam", url, run_id));
  declare_world(participant);
  coupler::SolidLink link(participant, scene, points);
  std::vector<Eigen::Vector3d> state(points, Eigen::Vector3d(0.1, 0.2, 0.3));
  while (true) {
    const auto window = participant.next_window();
    if (window.finish) {
      participant.finished("{}");
      return;
    }
    if (window.index > 0) link.ambient(window);
    link.publish_state(state, state, state);
    participant.done(1);
  }
}

void measure(int points, int windows, const std::string& scheme, int64_t run_id) {
  const auto scene = make_scene(windows, scheme);
  const std::string url = coupler::run_lcm_url(run_id);
  coupler::CouplerOptions coupler_options;
  coupler_options.url = url;
  coupler_options.run_id = run_id;
  coupler::Coupler coupler(scene, coupler_options);
  coupler::ProcessGroup none;
  std::thread flow(run_flow, std::cref(scene), url, run_id);
  std::thread solid(run_solid, std::cref(scene), url, run_id, points);
  const auto result = coupler.run(none);
  flow.join();
  solid.join();
  if (!result.ok) {
    fmt::print("{:>8} points {:<18} FAILED: {}\n", points, scheme, result.failure);
    return;
  }
  // Windows 1..N only: start-up (threads, handshake) and the final reports are not per window.
  const double per_window = result.windows_wall_seconds / windows;
  // Per window: 3 fields of 3N from the solid, 4N back from the flow.
  const double megabytes = 13.0 * points * 8 / 1e6;
  fmt::print(
      "{:>8} points {:<18} {:8.0f} windows/s  {:7.3f} ms/window  {:8.1f} MB/s  "
      "(whole run {:.3f} s)\n",
      points, scheme, 1.0 / per_window, per_window * 1e3, megabytes / per_window,
      result.wall_seconds);
}

}  // namespace

int main() {
  fmt::print("coupling overhead (coupler + flow + solid in one process, udpm loopback)\n");
  int64_t run_id = 91000 + static_cast<int64_t>(
                               std::chrono::steady_clock::now().time_since_epoch().count() % 1000);
  for (const int points : {10, 1000, 20000}) {
    const int windows = points > 5000 ? 100 : 400;
    for (const char* scheme : {"serial-explicit", "parallel-explicit"})
      measure(points, windows, scheme, ++run_id);
  }
  return 0;
}
