// The replay process: acts as a participant of a recorded run, publishing exactly what it
// published then, window by window, so another solver can be driven without its partners.
#include <spdlog/spdlog.h>

#include "cosim/coupler/process_main.hpp"
#include "cosim/replay/config.hpp"
#include "cosim/replay/recording.hpp"

int main(int argc, char** argv) {
  using namespace cosim;
  return coupler::run_process(argc, argv, "replay", [](coupler::ProcessContext& context) {
    auto section = context.section();
    const replay::ReplaySettings settings = replay::parse_settings(section);
    const replay::Recording recording =
        replay::read_recording(settings.event_log, settings.participant);
    spdlog::info("replaying '{}' from {} ({} windows recorded)", settings.participant,
                 settings.event_log.string(), recording.windows.size());
    auto& participant = *context.participant;
    // It stands in for the recorded participant, so it declares that one's frame.
    participant.declare(recording.declaration);
    while (true) {
      const coupler::Window window = participant.next_window();
      context.maybe_inject_fault(window.index);
      if (window.finish) {
        participant.finished(recording.metrics_json.empty() ? "{}" : recording.metrics_json);
        return;
      }
      const auto recorded = recording.windows.find(window.index);
      if (recorded == recording.windows.end() || !recorded->second.done) {
        throw std::runtime_error(fmt::format("{}: window {} of '{}' is not in the recording",
                                             settings.event_log.string(), window.index,
                                             settings.participant));
      }
      for (const auto& [field, values] : recorded->second.fields)
        participant.publish(field, values);
      participant.done(recorded->second.steps, recorded->second.stable_dt);
    }
  });
}
