// The replay process: acts as a participant of a recorded run, publishing exactly what it
// published then, window by window, so another solver can be driven without its partners.
#include <spdlog/spdlog.h>

#include "cosim/coupler/process_main.hpp"
#include "cosim/coupler/solver_loop.hpp"
#include "cosim/replay/config.hpp"
#include "cosim/replay/recording.hpp"

namespace {

using namespace cosim;

class ReplayProcess final : public coupler::Solver {
 public:
  explicit ReplayProcess(coupler::ProcessContext& context)
      : settings_(settings_of(context)),
        recording_(replay::read_recording(settings_.event_log, settings_.participant)),
        participant_(*context.participant) {
    spdlog::info("replaying '{}' from {} ({} windows recorded)", settings_.participant,
                 settings_.event_log.string(), recording_.windows.size());
    // It stands in for the recorded participant, so it declares that one's frame.
    participant_.declare(recording_.declaration);
  }

  coupler::WindowResult initial_window(const coupler::Window& window) override {
    return advance(window);
  }
  coupler::WindowResult advance(const coupler::Window& window) override {
    // Implicit schemes: every coupling iteration was recorded, and is played back as asked.
    const replay::WindowKey key{window.index, window.iteration};
    const auto recorded = recording_.windows.find(key);
    if (recorded == recording_.windows.end() || !recorded->second.done) {
      // Says what the recording does hold: a run that failed early ends before the scene does,
      // and a solver that changed may need other coupling iterations than the recorded ones.
      std::string held = "it holds no window";
      if (!recording_.windows.empty()) {
        held = fmt::format("it holds windows {} to {}", recording_.windows.begin()->first.window,
                           recording_.windows.rbegin()->first.window);
        const auto after = recording_.windows.lower_bound({window.index + 1, 0});
        if (window.iteration > 0 && after != recording_.windows.begin() &&
            std::prev(after)->first.window == window.index) {
          held += fmt::format("; window {} iterations 0 to {}", window.index,
                              std::prev(after)->first.iteration);
        }
      }
      throw std::runtime_error(fmt::format("{}: {} of '{}' is not in the recording ({})",
                                           settings_.event_log.string(), replay::describe(key),
                                           settings_.participant, held));
    }
    for (const auto& [field, values] : recorded->second.fields) participant_.publish(field, values);
    time_ = window.end_time();
    return {recorded->second.steps, recorded->second.stable_dt};
  }
  double output_time() const override { return time_; }
  // A replay plays windows by index from its log: its clock is all it keeps.
  void save_checkpoint(checkpoint::Writer& out) const override { out.value("replay.time", time_); }
  void load_checkpoint(const checkpoint::Reader& in) override {
    time_ = in.value<double>("replay.time");
  }
  void finish(coupler::MetricsReport& report) override {
    if (!recording_.metrics_json.empty()) report.merge(recording_.metrics_json);
  }

 private:
  static replay::ReplaySettings settings_of(coupler::ProcessContext& context) {
    scenario::Section section = context.section();
    return replay::parse_settings(section);
  }

  replay::ReplaySettings settings_;
  replay::Recording recording_;
  coupler::Participant& participant_;
  double time_ = 0.0;
};

}  // namespace

int main(int argc, char** argv) {
  return coupler::run_process(argc, argv, "replay", [](coupler::ProcessContext& context) {
    ReplayProcess replayed(context);
    coupler::run_solver_loop(context, replayed, 0.0);
  });
}
