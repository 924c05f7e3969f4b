// The coupler, the participant API and the links together, in one process over the run's
// multicast URL: a lossy network costs little time and changes nothing, and the event log keeps
// each message once, in the form the replay reads.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <functional>
#include <set>
#include <thread>

#include "cosim/coupler/coupler.hpp"
#include "cosim/coupler/event_log_file.hpp"
#include "cosim/coupler/frame.hpp"
#include "cosim/coupler/links.hpp"

namespace cosim::coupler {
namespace {

scenario::Scene make_scene(int windows) {
  scenario::Scene scene;
  scene.name = "coupling_run";
  scene.duration = windows * 1e-3;
  scene.coupling.window = 1e-3;
  scene.coupling.scheme = "serial-explicit";
  scene.coupling.timeout = 10.0;
  scene.participants = {
      {"prescribed_flow", "prescribed_flow", "prescribed_flow", scenario::Role::flow},
      {"vegetation_beam", "vegetation_beam", "vegetation_beam", scenario::Role::solid}};
  return scene;
}

ParticipantOptions options(const std::string& name, int64_t run_id, double loss) {
  ParticipantOptions participant;
  participant.name = name;
  participant.url = run_lcm_url(run_id);
  participant.run_id = run_id;
  participant.timeout = 10.0;
  participant.loss_probability = loss;
  participant.loss_seed = std::hash<std::string>{}(name) + 5;
  return participant;
}

// Answers every window with `answer` until the coupler asks for the finish (or aborts the run).
void serve_windows(Participant& participant, const std::function<void(const Window&)>& answer) {
  try {
    while (true) {
      const auto window = participant.next_window();
      if (window.finish) {
        participant.finished("{}");
        return;
      }
      answer(window);
    }
  } catch (const CouplingError&) {
    // the coupler aborted the run
  }
}

// The flow answers with a velocity that depends on where the points are, and the solid moves
// with it: a wrong or stale value anywhere changes the final state.
void run_flow(const scenario::Scene& scene, int64_t run_id, double loss) {
  Participant participant(options("prescribed_flow", run_id, loss));
  participant.declare(FrameDeclaration{}.to_json());
  FlowLink link(participant, scene);
  serve_windows(participant, [&](const Window& window) {
    for (const auto& solid : link.receive_solids(window)) {
      std::vector<Eigen::Vector3d> velocity;
      for (const auto& position : solid.positions) {
        velocity.emplace_back(std::sin(position.z()) + 0.1, 0.0, -0.01 * position.x());
      }
      link.publish_samples(solid.name, velocity, std::vector<double>(velocity.size(), 1.0));
    }
    participant.done(1);
  });
}

std::vector<Eigen::Vector3d> run_solid(const scenario::Scene& scene, int64_t run_id, double loss) {
  Participant participant(options("vegetation_beam", run_id, loss));
  participant.declare(FrameDeclaration{}.to_json());
  SolidLink link(participant, scene, 5);
  std::vector<Eigen::Vector3d> positions;
  for (int i = 0; i < 5; ++i) positions.emplace_back(0.0, 0.0, 0.01 * i);
  while (true) {
    const auto window = participant.next_window();
    if (window.finish) {
      participant.finished("{}");
      return positions;
    }
    if (window.index > 0) {
      const auto [begin, end] = link.ambient(window);
      for (std::size_t i = 0; i < positions.size(); ++i) {
        positions[i] += 0.5 * window.dt * (begin.velocity[i] + end.velocity[i]);
      }
    }
    link.publish_state(positions, positions, positions);
    participant.done(1);
  }
}

struct Outcome {
  RunResult result;
  std::vector<Eigen::Vector3d> final_positions;
};

Outcome run(int windows, double loss, int64_t run_id, const std::filesystem::path& log = {},
            RecordMode mode = RecordMode::all) {
  const auto scene = make_scene(windows);
  CouplerOptions coupler_options;
  coupler_options.url = run_lcm_url(run_id);
  coupler_options.run_id = run_id;
  coupler_options.loss_probability = loss;
  coupler_options.event_log = log;
  coupler_options.record_mode = mode;
  Coupler coupler(scene, coupler_options);
  ProcessGroup none;
  Outcome outcome;
  std::thread flow(run_flow, std::cref(scene), run_id, loss);
  std::thread solid([&] { outcome.final_positions = run_solid(scene, run_id, loss); });
  outcome.result = coupler.run(none);
  flow.join();
  solid.join();
  return outcome;
}

double seconds_of(const std::function<void()>& body) {
  const auto start = std::chrono::steady_clock::now();
  body();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST(CouplingRun, ThirtyPercentLossIsCheapAndChangesNothing) {
  Outcome clean;
  Outcome lossy;
  const double clean_seconds = seconds_of([&] { clean = run(300, 0.0, 5101); });
  const double lossy_seconds = seconds_of([&] { lossy = run(300, 0.3, 5102); });
  ASSERT_TRUE(clean.result.ok) << clean.result.failure;
  ASSERT_TRUE(lossy.result.ok) << lossy.result.failure;
  EXPECT_GT(lossy.result.traffic.dropped_injected, 100);
  ASSERT_EQ(clean.final_positions.size(), lossy.final_positions.size());
  for (std::size_t i = 0; i < clean.final_positions.size(); ++i) {
    EXPECT_EQ(std::memcmp(clean.final_positions[i].data(), lossy.final_positions[i].data(),
                          3 * sizeof(double)),
              0)
        << "point " << i;
  }
  // About 600 critical messages are lost; waiting out the 50 ms resend interval for each (as
  // before gap detection and beacons) took over 30 s. Loose bound: a shared 2-core machine.
  EXPECT_LT(lossy_seconds, 15.0) << "loss-free run took " << clean_seconds << " s";
}

TEST(CouplingRun, OverheadPerWindowIsReported) {
  const auto outcome = run(100, 0.0, 5103);
  ASSERT_TRUE(outcome.result.ok) << outcome.result.failure;
  EXPECT_EQ(outcome.result.windows_completed, 100);
  EXPECT_GT(outcome.result.windows_wall_seconds, 0.0);
  EXPECT_GE(outcome.result.overhead_seconds, 0.0);
  EXPECT_LE(outcome.result.overhead_seconds, outcome.result.windows_wall_seconds);
  EXPECT_GT(outcome.result.overhead_ms_per_window, 0.0);
  EXPECT_GE(outcome.result.overhead_fraction, 0.0);
  EXPECT_LE(outcome.result.overhead_fraction, 1.0);
  for (const auto& participant : outcome.result.participants) {
    EXPECT_EQ(participant.windows, 101) << participant.name;  // windows 0..100
    EXPECT_GE(participant.physics_seconds, 0.0) << participant.name;
  }
}

struct LogContents {
  std::size_t field_events = 0;
  std::size_t status_events = 0;
  std::size_t duplicates = 0;
  std::size_t housekeeping = 0;  // beacons and resend requests
};

LogContents read_log(const std::filesystem::path& file) {
  LogContents contents;
  EventLogReader log(file);
  EXPECT_TRUE(log.compressed()) << file;
  std::set<std::pair<std::string, int64_t>> seen;
  while (const auto event = log.next()) {
    cosim_msgs::header_t header;
    int64_t hash = 0;
    if (event->channel == kFieldChannel) {
      ++contents.field_events;
      hash = cosim_msgs::field_chunk_t::getHash();
    } else if (event->channel == kStatusChannel) {
      ++contents.status_events;
      hash = cosim_msgs::status_t::getHash();
    } else if (event->channel == kWindowChannel) {
      hash = cosim_msgs::window_t::getHash();
    } else {
      ++contents.housekeeping;
      continue;
    }
    if (!peek_header(event->data.data(), static_cast<int>(event->data.size()), hash, header)) {
      continue;
    }
    // Inline fields are logged as chunks carrying their report's sequence number.
    if (event->channel == kFieldChannel) continue;
    if (!seen.insert({header.sender, header.sequence}).second) ++contents.duplicates;
  }
  return contents;
}

TEST(CouplingRun, TheLogKeepsEachMessageOnceAndControlLeavesFieldsOut) {
  const auto folder = std::filesystem::temp_directory_path() / "cosim_coupling_run_test";
  std::filesystem::create_directories(folder);
  const auto all_log = folder / "all.lcmlog.zst";
  const auto control_log = folder / "control.lcmlog.zst";
  ASSERT_TRUE(run(100, 0.2, 5104, all_log, RecordMode::all).result.ok);
  ASSERT_TRUE(run(100, 0.0, 5105, control_log, RecordMode::control).result.ok);
  const auto all = read_log(all_log);
  const auto control = read_log(control_log);
  EXPECT_EQ(all.duplicates, 0u) << "a retransmission was recorded twice";
  EXPECT_EQ(all.housekeeping, 0u);
  // 101 windows x (3 solid fields + 3 flow samples), each once.
  EXPECT_EQ(all.field_events, 101u * 6u);
  EXPECT_EQ(control.field_events, 0u);
  EXPECT_GT(control.status_events, 2u * 101u - 1u);
  // Compared before compression (these test fields are copies of each other and compress to
  // almost nothing).
  auto raw_bytes = [](const std::filesystem::path& file) {
    EventLogReader reader(file);
    uint64_t sum = 0;
    for (const auto& block : reader.blocks()) sum += block.raw_size;
    return sum;
  };
  EXPECT_LT(raw_bytes(control_log) * 3, raw_bytes(all_log));
  std::filesystem::remove_all(folder);
}

// Adaptive windows: the flow limits the window (its stable dt shrinks window by window), the
// solid does not. Window k + 1 must be granted to the flow as soon as the flow has reported
// window k, while the solid still computes window k: the solid waits, before it reports window
// k, until the flow holds the grant of k + 1. A coupler that sizes windows only once everyone
// has reported never grants it and the solid gives up waiting.
struct AdaptiveOutcome {
  RunResult result;
  std::vector<double> solid_dts;  // window lengths the solid was given, windows 1..
  int grants_missed = 0;          // windows in which the flow's grant of k + 1 never came
};

double flow_stable_dt(int64_t window) {
  return 1e-3 / (1.0 + 0.05 * static_cast<double>(window));
}

AdaptiveOutcome run_adaptive(int64_t run_id, bool flow_limits) {
  scenario::Scene scene = make_scene(20);
  scene.coupling.adaptive_window = true;
  scene.coupling.timeout = 5.0;
  CouplerOptions coupler_options;
  coupler_options.url = run_lcm_url(run_id);
  coupler_options.run_id = run_id;
  Coupler coupler(scene, coupler_options);
  std::atomic<int64_t> flow_granted{-1};
  AdaptiveOutcome outcome;
  std::thread flow([&] {
    Participant participant(options("prescribed_flow", run_id, 0.0));
    FrameDeclaration declaration;
    declaration.limits_window = flow_limits;
    participant.declare(declaration.to_json());
    FlowLink link(participant, scene);
    serve_windows(participant, [&](const Window& window) {
      flow_granted = window.index;
      for (const auto& solid : link.receive_solids(window)) {
        link.publish_samples(
            solid.name,
            std::vector<Eigen::Vector3d>(solid.positions.size(), Eigen::Vector3d(0.1, 0.0, 0.0)),
            std::vector<double>(solid.positions.size(), 1.0));
      }
      participant.done(1, flow_stable_dt(window.index));
    });
  });
  std::thread solid([&] {
    Participant participant(options("vegetation_beam", run_id, 0.0));
    participant.declare(FrameDeclaration{}.to_json());
    SolidLink link(participant, scene, 2);
    const std::vector<Eigen::Vector3d> positions(2, Eigen::Vector3d::Zero());
    serve_windows(participant, [&](const Window& window) {
      if (window.index > 0) {
        link.ambient(window);
        outcome.solid_dts.push_back(window.dt);
        const bool last = window.end_time() >= scene.duration * (1.0 - 1e-9);
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
        while (!last && flow_granted < window.index + 1 &&
               std::chrono::steady_clock::now() < until) {
          std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
        if (!last && flow_granted < window.index + 1) ++outcome.grants_missed;
      }
      link.publish_state(positions, positions, positions);
      participant.done(1);
    });
  });
  ProcessGroup none;
  outcome.result = coupler.run(none);
  flow.join();
  solid.join();
  return outcome;
}

TEST(CouplingRun, AnAdaptiveWindowIsGrantedWhileTheOthersStillCompute) {
  const auto outcome = run_adaptive(5106, true);
  ASSERT_TRUE(outcome.result.ok) << outcome.result.failure;
  EXPECT_EQ(outcome.grants_missed, 0)
      << "the flow waited for the solid's report before it was given the next window";
  // The plan is the one the flow's stable dts make: window k + 1 as long as window k allowed.
  ASSERT_GE(outcome.solid_dts.size(), 10u);
  EXPECT_EQ(outcome.solid_dts[0], 1e-3);  // window 1 from window 0's stable dt: 1e-3
  for (std::size_t k = 1; k + 1 < outcome.solid_dts.size(); ++k) {
    EXPECT_EQ(outcome.solid_dts[k], flow_stable_dt(static_cast<int64_t>(k))) << "window " << k + 1;
  }
}

TEST(CouplingRun, AStableDtFromAParticipantThatDeclaredNoLimitStopsTheRun) {
  const auto outcome = run_adaptive(5107, false);
  EXPECT_FALSE(outcome.result.ok);
  EXPECT_NE(outcome.result.failure.find("'prescribed_flow' reported a stable dt of 0.001 s in "
                                        "window 0 (t = 0 s) but declared at the handshake that "
                                        "it does not limit the window"),
            std::string::npos)
      << outcome.result.failure;
}

// A run of `scene` with a flow and a three-point resolved solid in two threads (rolling back
// under an implicit scheme): the flow hands `seen` each solid's view of every window it runs and
// answers with zero samples and loads; the solid publishes what `state` gives for the window.
struct SolidAnswer {
  std::vector<Eigen::Vector3d> start, end, velocity;  // start empty: publish_state
};
RunResult run_resolved_solid(const scenario::Scene& scene, int64_t run_id,
                             const std::function<void(const Window&, const SolidForcing&)>& seen,
                             const std::function<SolidAnswer(const Window&)>& state) {
  const bool rollback = scene.coupling.scheme.find("implicit") != std::string::npos;
  CouplerOptions coupler_options;
  coupler_options.url = run_lcm_url(run_id);
  coupler_options.run_id = run_id;
  Coupler coupler(scene, coupler_options);
  std::thread flow([&] {
    auto opts = options("prescribed_flow", run_id, 0.0);
    opts.rollback = rollback;
    Participant participant(opts);
    participant.declare(FrameDeclaration{}.to_json());
    FlowLink link(participant, scene);
    serve_windows(participant, [&](const Window& window) {
      for (const auto& solid : link.receive_solids(window)) {
        seen(window, solid);
        const std::vector<Eigen::Vector3d> zero(solid.positions.size(), Eigen::Vector3d::Zero());
        link.publish_samples(solid.name, zero, std::vector<double>(zero.size(), 1.0));
        link.publish_fluid_load(solid.name, zero);
      }
      participant.done(1);
    });
  });
  std::thread solid([&] {
    auto opts = options("vegetation_beam", run_id, 0.0);
    opts.rollback = rollback;
    Participant participant(opts);
    participant.declare(FrameDeclaration{}.to_json());
    SolidLink link(participant, scene, 3);
    serve_windows(participant, [&](const Window& window) {
      if (window.index > 0) link.ambient(window);
      const auto answer = state(window);
      const std::vector<Eigen::Vector3d> drag(answer.end.size(), Eigen::Vector3d::Zero());
      if (answer.start.empty()) {
        link.publish_state(answer.end, answer.velocity, drag);
      } else {
        link.publish_window_state(answer.start, window.dt, answer.end, answer.velocity, drag);
      }
      participant.done(1);
    });
  });
  ProcessGroup none;
  const auto result = coupler.run(none);
  flow.join();
  solid.join();
  return result;
}

// coupling.resolved_plants under serial-implicit (exchange::resolved_path): the flow moves the
// solid's wall from where the solid started the window. The first iteration, like the explicit
// scheme, extrapolates the window-start state; the next ones go from the accepted start to the
// iterate's end. (Put at the iterate's end and moved on with its velocity, the wall ran a whole
// window ahead of the solid.)
TEST(CouplingRun, AResolvedSolidsWallGoesFromTheAcceptedStartToTheIterate) {
  const int64_t run_id = 5108;
  auto scene = make_scene(6);
  scene.coupling.scheme = "serial-implicit";
  scene.coupling.implicit.acceleration = scenario::Acceleration::none;
  scene.coupling.implicit.max_iterations = 3;
  scene.coupling.interface.resolved_plants = true;
  const double dt = scene.coupling.window, speed = 5.0, step = 0.002;  // step / dt = 2 m/s
  // The solid's end of window k, whatever the flow does: x_k = (step k, 0, 0.01 i), v = speed.
  auto position = [&](int64_t k, int i) { return Eigen::Vector3d(step * k, 0.0, 0.01 * i); };
  struct Seen {
    int64_t window;
    int32_t iteration;
    std::vector<Eigen::Vector3d> start, velocity;
  };
  std::vector<Seen> seen;
  const auto result = run_resolved_solid(
      scene, run_id,
      [&](const Window& window, const SolidForcing& solid) {
        if (window.dt > 0.0) {
          seen.push_back({window.index, window.iteration, solid.path_start, solid.path_velocity});
        }
      },
      [&](const Window& window) {
        SolidAnswer answer;
        for (int i = 0; i < 3; ++i) {
          answer.end.push_back(position(window.index, i));
          answer.velocity.emplace_back(speed, 0.0, 0.0);
        }
        return answer;
      });
  ASSERT_TRUE(result.ok) << result.failure;
  int later_iterations = 0;
  for (const auto& s : seen) {
    ASSERT_EQ(s.start.size(), 3u);
    ASSERT_EQ(s.velocity.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const std::string where =
          "window " + std::to_string(s.window) + " iteration " + std::to_string(s.iteration);
      EXPECT_LT((s.start[i] - position(s.window - 1, i)).norm(), 1e-15) << where;
      const Eigen::Vector3d expected =
          s.iteration == 0
              ? Eigen::Vector3d(speed, 0.0, 0.0)
              : Eigen::Vector3d((position(s.window, i) - position(s.window - 1, i)) / dt);
      EXPECT_LT((s.velocity[i] - expected).norm(), 1e-12) << where;
    }
    if (s.iteration > 0) ++later_iterations;
  }
  EXPECT_GE(later_iterations, 6) << "every window iterates at least twice";
}

// A resolved solid's velocities are not read by the flow after the first iteration (the wall
// goes along the positions, above), so the coupler relaxes only its positions and passes the
// velocities on as the solid answered: relaxed with the positions, they trailed the solid's
// answer by (1 - omega)^i and held the window's convergence measure up long after the positions
// had converged (light_blade_bed: 5 windows of 150 at the iteration limit, 8.8 iterations a
// window; passed on: none, 5.1).
TEST(CouplingRun, AResolvedSolidsVelocitiesPassOnAsTheSolidAnswered) {
  const int64_t run_id = 5109;
  auto scene = make_scene(4);
  scene.coupling.scheme = "serial-implicit";
  scene.coupling.implicit.acceleration = scenario::Acceleration::constant;
  scene.coupling.implicit.relaxation = 0.5;
  scene.coupling.implicit.max_iterations = 4;
  scene.coupling.interface.resolved_plants = true;
  // The solid's answer in iteration i of window k: positions (0.001 (k + i), 0, 0.01 j), velocity
  // (1 + i, 0, 0): it never converges, so every window runs all four iterations.
  auto answer_position = [](int64_t k, int32_t i, int j) {
    return Eigen::Vector3d(0.001 * static_cast<double>(k + i), 0.0, 0.01 * j);
  };
  struct Seen {
    int64_t window;
    int32_t iteration;
    std::vector<Eigen::Vector3d> positions, velocities;
  };
  std::vector<Seen> seen;
  const auto result = run_resolved_solid(
      scene, run_id,
      [&](const Window& window, const SolidForcing& solid) {
        seen.push_back({window.index, window.iteration, solid.positions, solid.velocities});
      },
      [&](const Window& window) {
        SolidAnswer answer;
        for (int j = 0; j < 3; ++j) {
          answer.end.push_back(answer_position(window.index, window.iteration, j));
          answer.velocity.emplace_back(1.0 + window.iteration, 0.0, 0.0);
        }
        return answer;
      });
  ASSERT_TRUE(result.ok) << result.failure;
  int later_iterations = 0;
  std::vector<Eigen::Vector3d> input;  // the positions the flow read in the iteration before
  for (const auto& s : seen) {
    ASSERT_EQ(s.velocities.size(), 3u);
    const std::string where =
        "window " + std::to_string(s.window) + " iteration " + std::to_string(s.iteration);
    for (int j = 0; s.iteration > 0 && j < 3; ++j) {
      // Velocities: the solid's answer of iteration i - 1, not relaxed.
      EXPECT_EQ(s.velocities[static_cast<std::size_t>(j)].x(), 1.0 + (s.iteration - 1)) << where;
      // Positions: relaxed by 0.5 between the input and the answer of iteration i - 1.
      const Eigen::Vector3d expected = 0.5 * (input[static_cast<std::size_t>(j)] +
                                              answer_position(s.window, s.iteration - 1, j));
      EXPECT_LT((s.positions[static_cast<std::size_t>(j)] - expected).norm(), 1e-15) << where;
    }
    if (s.iteration > 0) ++later_iterations;
    input = s.positions;
  }
  EXPECT_GE(later_iterations, 9) << "three windows of three later iterations";
}

// The wall path of a window's first iteration (exchange::resolved_velocity): under an implicit
// scheme the solid hands the flow its window-mean velocity, so the first iteration extrapolates
// the converged positions; an explicit scheme keeps the velocity at the window's end. The solid
// here moves 2 mm a window but reports 5 m/s at every window's end (a fast vibration the window
// does not see).
std::vector<std::pair<int64_t, Eigen::Vector3d>> first_iteration_wall_velocities(
    const std::string& scheme, int64_t run_id) {
  auto scene = make_scene(4);
  scene.coupling.scheme = scheme;
  scene.coupling.implicit.acceleration = scenario::Acceleration::none;
  scene.coupling.implicit.max_iterations = 2;
  scene.coupling.interface.resolved_plants = true;
  auto position = [](int64_t k) { return Eigen::Vector3d(0.002 * static_cast<double>(k), 0, 0); };
  std::vector<std::pair<int64_t, Eigen::Vector3d>> seen;
  const auto result = run_resolved_solid(
      scene, run_id,
      [&](const Window& window, const SolidForcing& solid) {
        if (window.dt > 0.0 && window.iteration == 0) {
          seen.emplace_back(window.index, solid.path_velocity.at(0));
        }
      },
      [&](const Window& window) {
        SolidAnswer answer;
        for (int j = 0; j < 3; ++j) {
          answer.end.push_back(position(window.index) + Eigen::Vector3d(0, 0, 0.01 * j));
          // Window 0 (no window behind it): at rest; later ones vibrate at their end.
          answer.velocity.emplace_back(window.index == 0 ? 0.0 : 5.0, 0.0, 0.0);
          if (window.index > 0) {
            answer.start.push_back(position(window.index - 1) + Eigen::Vector3d(0, 0, 0.01 * j));
          }
        }
        return answer;
      });
  EXPECT_TRUE(result.ok) << result.failure;
  return seen;
}

TEST(CouplingRun, AnImplicitWindowStartsAResolvedWallAtTheSolidsMeanVelocity) {
  const auto implicit = first_iteration_wall_velocities("serial-implicit", 5110);
  ASSERT_GE(implicit.size(), 3u);
  for (const auto& [window, velocity] : implicit) {
    // Window 1 starts from window 0's state (at rest); later ones from 2 mm per 1 ms window.
    const Eigen::Vector3d expected(window == 1 ? 0.0 : 2.0, 0.0, 0.0);
    EXPECT_LT((velocity - expected).norm(), 1e-12) << "window " << window;
  }
  const auto explicit_run = first_iteration_wall_velocities("serial-explicit", 5111);
  ASSERT_GE(explicit_run.size(), 3u);
  for (const auto& [window, velocity] : explicit_run) {
    const Eigen::Vector3d expected(window == 1 ? 0.0 : 5.0, 0.0, 0.0);
    EXPECT_LT((velocity - expected).norm(), 1e-12) << "window " << window;
  }
}

}  // namespace
}  // namespace cosim::coupler
