// The prescribed_flow process: answers every solid's samples from an analytic flow field, so a
// solid solver can run without a fluid solver (seed 004 does exactly that).
#include <nlohmann/json.hpp>

#include "cosim/coupler/links.hpp"
#include "cosim/coupler/process_main.hpp"
#include "cosim/coupler/solver_loop.hpp"
#include "cosim/prescribed_flow/config.hpp"

namespace {

using namespace cosim;

class PrescribedFlowProcess final : public coupler::Solver {
 public:
  explicit PrescribedFlowProcess(coupler::ProcessContext& context)
      : flow_(settings_of(context)), link_(*context.participant, context.scene) {}

  coupler::WindowResult initial_window(const coupler::Window& window) override {
    return advance(window);
  }
  coupler::WindowResult advance(const coupler::Window& window) override {
    for (const auto& solid : link_.receive_solids(window)) {
      // The flow cannot move, but it books the impulse the solids took from it by the link's
      // rule (for momentum checks: minus the impulse a real fluid would have received).
      for (const auto& reaction : solid.reaction) impulse_on_solids_ -= reaction * window.dt;
      flow_.sample(window.end_time(), solid.positions, velocity_, water_);
      link_.publish_samples(solid.name, velocity_, water_);
    }
    time_ = window.end_time();
    return {1, 0.0};
  }
  double output_time() const override { return time_; }
  // The analytic flow keeps nothing but its clock and the impulse it booked.
  void save_checkpoint(checkpoint::Writer& out) const override {
    out.value("prescribed_flow.time", time_);
    out.value("prescribed_flow.impulse_on_solids", impulse_on_solids_);
    link_.save_checkpoint(out);
  }
  void load_checkpoint(const checkpoint::Reader& in) override {
    time_ = in.value<double>("prescribed_flow.time");
    impulse_on_solids_ = in.value<Eigen::Vector3d>("prescribed_flow.impulse_on_solids");
    link_.load_checkpoint(in);
  }
  void finish(coupler::MetricsReport& report) override {
    report.info()["profile"] = prescribed_flow::profile_kind_name(flow_.settings().kind);
    report.info()["impulse_on_solids"] = {impulse_on_solids_.x(), impulse_on_solids_.y(),
                                          impulse_on_solids_.z()};
  }

 private:
  static prescribed_flow::ProfileSettings settings_of(coupler::ProcessContext& context) {
    scenario::Section section = context.section();
    return prescribed_flow::parse_settings(section);
  }

  const prescribed_flow::PrescribedFlow flow_;
  coupler::FlowLink link_;
  Eigen::Vector3d impulse_on_solids_ = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> velocity_;
  std::vector<double> water_;
  double time_ = 0.0;
};

}  // namespace

int main(int argc, char** argv) {
  return cosim::coupler::run_process(argc, argv, "prescribed_flow",
                                     [](cosim::coupler::ProcessContext& context) {
                                       PrescribedFlowProcess flow(context);
                                       cosim::coupler::run_solver_loop(context, flow, 0.0);
                                     });
}
