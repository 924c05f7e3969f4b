// The prescribed_flow process: answers every solid's samples from an analytic flow field, so a
// solid solver can run without a fluid solver (seed 004 does exactly that).
#include <nlohmann/json.hpp>

#include "cosim/coupler/links.hpp"
#include "cosim/coupler/process_main.hpp"
#include "cosim/prescribed_flow/config.hpp"

int main(int argc, char** argv) {
  using namespace cosim;
  return coupler::run_process(argc, argv, "prescribed_flow", [](coupler::ProcessContext& context) {
    auto section = context.section();
    const prescribed_flow::PrescribedFlow flow(prescribed_flow::parse_settings(section));
    auto& participant = *context.participant;
    coupler::FlowLink link(participant, context.scene);
    // The flow cannot move, but it books the impulse the solids took from it by the link's rule
    // (for momentum checks: minus the impulse a real fluid would have received).
    Eigen::Vector3d impulse_on_solids = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> velocity;
    std::vector<double> water;
    while (true) {
      const coupler::Window window = participant.next_window();
      context.maybe_inject_fault(window.index);
      if (window.finish) {
        nlohmann::json metrics;
        metrics["profile"] = prescribed_flow::profile_kind_name(flow.settings().kind);
        metrics["impulse_on_solids"] = {impulse_on_solids.x(), impulse_on_solids.y(),
                                        impulse_on_solids.z()};
        participant.finished(metrics.dump());
        return;
      }
      for (const auto& solid : link.receive_solids(window)) {
        for (const auto& reaction : solid.reaction) impulse_on_solids -= reaction * window.dt;
        flow.sample(window.end_time(), solid.positions, velocity, water);
        link.publish_samples(solid.name, velocity, water);
      }
      participant.done(1);
    }
  });
}
