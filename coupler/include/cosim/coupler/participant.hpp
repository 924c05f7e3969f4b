// The one API every solver process uses to take part in a coupled run. A solver calls
// next_window(), receives what it needs from its partners, computes, publishes its fields and
// calls done(). Retransmission, heartbeats and timeouts are handled here, so a lost message
// never hangs or corrupts a run and a silent partner is reported by name.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cosim/coupler/bus.hpp"

namespace cosim::coupler {

// The run cannot go on: a partner fell silent, the coupler aborted, or a message was malformed.
class CouplingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ParticipantOptions {
  std::string name;  // the name this participant publishes under
  std::string url;
  int64_t run_id = 0;
  double timeout = 5.0;           // seconds of partner silence before giving up
  double resend_interval = 0.05;  // seconds between retransmission requests
  int chunk_values = 4096;
  double loss_probability = 0.0;
  uint64_t loss_seed = 1;
  // Implicit schemes: the window before the one being iterated can still be saved (from the
  // window-start state every iteration rolls back to), as a run interrupted mid-window needs.
  bool rollback = false;
};

struct Window {
  int64_t index = 0;  // 0 is the initialisation window (dt = 0)
  double time = 0.0;  // start of the window
  double dt = 0.0;
  int64_t total_windows = 0;
  bool finish = false;  // the coupler asks for final outputs and metrics
  // Not a window to run: write a checkpoint of the state after window `index` (just done).
  bool checkpoint = false;
  // A checkpoint asked while window index + 1 is being iterated (implicit schemes): the state
  // after window `index` is the start of that window, which the solver rolls back to first.
  bool rolled_back = false;
  // Implicit schemes: the coupling iteration of this window (each starts from the window-start
  // state), and the iteration the coupler accepted for window index - 1. 0 for explicit schemes.
  int32_t iteration = 0;
  int32_t accepted_iteration = 0;
  double end_time() const { return time + dt; }
};

class Participant {
 public:
  explicit Participant(ParticipantOptions options);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  const std::string& name() const { return options_.name; }

  // The frame, dimension, span and gravity this participant computes in, sent with its answer
  // to the handshake; the coupler refuses to start a run whose participants disagree. Call it
  // before the first next_window().
  void declare(const std::string& declaration_json) { declaration_ = declaration_json; }

  // A restarted participant's first window is `window`: the one its checkpoint was written
  // after, run again with dt 0 to publish the saved fields (run_solver_loop). Call before the
  // first next_window().
  void start_at(int64_t window);
  // Waits for the next window (answering the handshake and repeated windows on the way). When
  // the coupler asked for a checkpoint after the window just done, returns that first, with
  // `checkpoint` set.
  Window next_window();
  // After a checkpoint window: the state is written; `description_json` (file, bytes, seconds)
  // goes to the coupler for the manifest.
  void checkpointed(const std::string& description_json, int64_t window);
  // Every field published in the current window, in order (a checkpoint keeps them, so a
  // restarted run hands its partners exactly what they would have received).
  const std::vector<std::pair<std::string, std::vector<double>>>& published_fields() const {
    return window_fields_;
  }
  // With `rollback` (implicit schemes): every field published in the previous window's last
  // iteration, the one the coupler accepted (what a checkpoint of that window keeps).
  const std::vector<std::pair<std::string, std::vector<double>>>& previous_window_fields() const {
    return previous_window_fields_;
  }
  // Publishes a field for the current window. Fields that fit into one message together travel
  // inside the window's DONE report; larger ones go out at once in chunks.
  void publish(const std::string& field, std::span<const double> values);
  // Waits for `sender`'s field of `window`, asking for lost chunks again. Throws CouplingError
  // when the sender stays silent longer than the timeout, or the coupler aborts.
  std::vector<double> receive(const std::string& sender, const std::string& field, int64_t window,
                              int32_t iteration = 0);
  // Marks the current window done. `steps`: solver steps taken (sub-steps for solids);
  // stable_dt: the largest next window this participant accepts (0 for no limit).
  void done(int steps, double stable_dt = 0.0);
  // Final report after the FINISH window: metrics as a JSON object text.
  void finished(const std::string& metrics_json);
  // Reports a failure to the coupler (several times, since it may be lost) before exiting.
  void failed(const std::string& message);

  // Time accounting: compute time is everything outside waiting for partners.
  double wait_seconds() const { return wait_seconds_; }
  double compute_seconds() const;
  // Wall time outside every call of this API (what the solver itself spent) [s].
  double physics_seconds() const;
  // CPU time of this process, every thread (OpenMP workers, heartbeat) included [s].
  double cpu_seconds() const;
  int64_t total_steps() const { return total_steps_; }
  Bus& bus() { return *bus_; }

 private:
  void publish_state(int8_t state, int steps, double stable_dt, const std::string& message);
  // The answer that the checkpoint after `window` is written (its file, bytes, seconds).
  void publish_checkpointed(int64_t window, const std::string& description_json);
  void heartbeat_loop();
  void check_abort();
  void flush_inline_fields();
  void take_checkpoint_requests(const cosim_msgs::window_t& message);
  Stamp stamp() const;
  // Adds the time of one API call to api_seconds_.
  class ApiTimer {
   public:
    explicit ApiTimer(Participant& owner);
    ~ApiTimer();
    ApiTimer(const ApiTimer&) = delete;
    ApiTimer& operator=(const ApiTimer&) = delete;

   private:
    Participant& owner_;
    std::chrono::steady_clock::time_point start_;
  };

  ParticipantOptions options_;
  std::string declaration_;
  std::unique_ptr<Bus> bus_;
  Window current_;
  bool current_done_ = false;
  int last_steps_ = 0;
  double last_stable_dt_ = 0.0;
  double wait_seconds_ = 0.0;
  double api_seconds_ = 0.0;
  int64_t total_steps_ = 0;
  // Windows the coupler has granted and not yet run; the FINISH once it came.
  std::map<std::pair<int64_t, int32_t>, Window> granted_;  // by (window, iteration)
  std::optional<Window> finish_;
  // This window's fields, for its DONE report.
  std::vector<cosim_msgs::field_t> pending_fields_;
  std::size_t pending_inline_values_ = 0;
  std::vector<std::pair<std::string, std::vector<double>>> window_fields_;
  std::vector<std::pair<std::string, std::vector<double>>> previous_window_fields_;
  // Checkpoints asked for and not yet written; those written, with their answer (repeated when
  // the coupler asks again: an answer may be lost).
  std::set<int64_t> checkpoint_requests_;
  std::map<int64_t, std::string> checkpoints_written_;
  std::chrono::steady_clock::time_point last_checkpoint_answer_{};
  std::chrono::steady_clock::time_point started_;
  std::chrono::steady_clock::time_point last_ready_{};
  std::atomic<bool> stop_heartbeat_{false};
  std::atomic<int64_t> heartbeat_window_{-1};
  std::thread heartbeat_;
};

}  // namespace cosim::coupler
