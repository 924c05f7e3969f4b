// The transport under the participant API and the coupler: LCM publish/receive with message
// headers, run isolation, duplicate dropping, chunked float64 fields, reliable delivery by
// sequence numbers (a receiver that sees a gap, or hears a beacon naming a sequence number it
// never got, asks for exactly those messages at once; the sender republishes them byte for
// byte), optional recording of the traffic to an event log, and optional injected loss (for
// tests that prove a lossy network never changes a result).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "cosim_msgs/beacon_t.hpp"
#include "cosim_msgs/field_chunk_t.hpp"
#include "cosim_msgs/resend_request_t.hpp"
#include "cosim_msgs/status_t.hpp"
#include "cosim_msgs/window_t.hpp"

namespace cosim::coupler {

class EventRecorder;

inline constexpr const char* kWindowChannel = "COSIM_WINDOW";
inline constexpr const char* kStatusChannel = "COSIM_STATUS";
inline constexpr const char* kFieldChannel = "COSIM_FIELD";
inline constexpr const char* kResendChannel = "COSIM_RESEND";
inline constexpr const char* kBeaconChannel = "COSIM_BEACON";

// Hash over every message type of the protocol: peers built from other .lcm files disagree.
int64_t protocol_schema_hash();

// The LCM URL of a run: a port and multicast group derived from the run id, so concurrent runs
// do not hear each other; a large receive buffer because UDP loses big bursts otherwise.
// `ttl` is the multicast time-to-live: 0 keeps the run on this host, 1 reaches the hosts of the
// local network (a run with participants on other machines, `cosim run --remote`).
std::string run_lcm_url(int64_t run_id, int ttl = 0);

// Decodes only the header of an encoded message of type `type_hash` (cheap for large chunks).
bool peek_header(const void* data, int size, int64_t type_hash, cosim_msgs::header_t& header);

// What goes into the event log: every message, only the protocol's control messages (windows
// and reports without field values), or nothing.
enum class RecordMode { all, control, none };
RecordMode parse_record_mode(const std::string& text);  // throws naming the choices
const char* record_mode_name(RecordMode mode);

struct BusOptions {
  std::string url;
  int64_t run_id = 0;
  std::string name;               // own participant name (sender of what we publish)
  int chunk_values = 4096;        // float64 values per field chunk
  double loss_probability = 0.0;  // injected loss of received messages (tests)
  uint64_t loss_seed = 1;
  std::filesystem::path record_log;  // when set, the traffic heard is written here
  RecordMode record_mode = RecordMode::all;
  int cached_windows = 4;         // windows of own messages kept for retransmission
  double resend_interval = 0.05;  // longest wait between two requests for a lost message [s]
  bool keep_fields = true;        // false: never assemble fields (the coupler only records them)
};

// Who, when and where a message belongs, as stamped into its header.
struct Stamp {
  int64_t window = 0;
  double sim_time = 0.0;
  double dt = 0.0;
  int32_t iteration = 0;  // coupling iteration inside the window (implicit schemes)
};

struct FieldKey {
  std::string sender;
  int64_t window;
  std::string field;
  int32_t iteration = 0;  // implicit schemes publish a window's fields once per iteration
  auto operator<=>(const FieldKey&) const = default;
};

class Bus {
 public:
  explicit Bus(BusOptions options);
  ~Bus();
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  const std::string& name() const { return options_.name; }
  const BusOptions& options() const { return options_; }

  // Publishing. Thread-safe (a heartbeat thread publishes while the main thread computes).
  // `windows`: for ADVANCE, the (start time, length) of windows stamp.window, stamp.window + 1...
  // `checkpoints`: windows after which every participant writes a checkpoint.
  void publish_window(const Stamp& stamp, int8_t command, int64_t total_windows,
                      const std::string& reason = "",
                      const std::vector<std::pair<double, double>>& windows = {},
                      const std::vector<int64_t>& checkpoints = {}, int32_t accepted_iteration = 0);
  // Fields inside the status (field_t with chunk_count 0) are delivered with it.
  void publish_status(const Stamp& stamp, cosim_msgs::status_t status);
  // Splits values into chunks and publishes them now. `as_sender` lets a replay driver publish
  // under the recorded participant's name. Returns the number of chunks.
  int32_t publish_field(const Stamp& stamp, const std::string& field,
                        std::span<const double> values, const std::string& as_sender = "");

  // Asks `key.sender` for every message that carried the field: the fallback of a receiver
  // that waited a whole resend interval for it.
  void request_field(const FieldKey& key);

  // Receives for up to `seconds`; returns true as soon as any message was accepted. Also asks
  // for lost messages again and sends beacons when they are due.
  bool poll(double seconds);
  // Sends a beacon if one is due; waits at most until `deadline` for one to become due (the
  // heartbeat thread calls this while the main thread computes). Returns when the deadline
  // passed or wake() was called.
  void beacon_until(std::chrono::steady_clock::time_point deadline);
  void wake();

  // Received messages, oldest first; the caller pops what it consumes.
  std::deque<cosim_msgs::window_t>& windows() { return windows_; }
  std::deque<cosim_msgs::status_t>& statuses() { return statuses_; }

  // A complete field, or nothing yet.
  std::optional<std::vector<double>> field_values(const FieldKey& key);
  bool has_field(const FieldKey& key) const;
  std::vector<int32_t> missing_chunks(const FieldKey& key) const;  // empty list: nothing heard
  // Every complete field heard, without consuming (replay comparison).
  const std::map<FieldKey, std::vector<double>>& completed_fields() const { return completed_; }
  void forget_fields_before(int64_t window);

  // When we last accepted any message from a sender (steady clock).
  std::optional<std::chrono::steady_clock::time_point> last_heard(const std::string& sender) const;

  // Drops the next `count` data messages (window, status, field) of this run from other
  // participants, as a lossy network would (tests). Beacons, resend requests and other runs'
  // messages pass.
  void drop_next(int count) { drop_next_ += count; }

  // Extra names this bus publishes as and therefore ignores when heard back (replay driver).
  void add_own_name(const std::string& name) { own_names_.insert(name); }

  // What the transport knows of a sender, for diagnostics of a long wait.
  std::string describe_peer(const std::string& sender) const;

  // Current estimate of how long a request for a lost message takes to be answered [s].
  double retransmit_timeout() const { return rto_.load(); }

  struct Counters {
    int64_t accepted = 0;
    int64_t dropped_injected = 0;
    int64_t dropped_foreign = 0;
    int64_t dropped_duplicate = 0;
    int64_t resends_served = 0;
    int64_t resends_requested = 0;  // sequence numbers asked for again
    int64_t gaps_detected = 0;      // messages found missing (sequence gap or beacon)
    int64_t beacons_sent = 0;
  };
  Counters counters() const;

 private:
  using Clock = std::chrono::steady_clock;
  // Gaps wider than this are not a lost message but a sender we started hearing late.
  static constexpr int64_t kLargestGap = 4096;
  struct Assembly {
    int32_t chunk_count = 0;
    int64_t total_values = 0;
    std::vector<double> values;
    std::vector<bool> received;
    int32_t received_count = 0;
  };
  // A message of ours, kept encoded so a resend is byte for byte the original.
  struct Cached {
    std::string channel;
    std::vector<uint8_t> bytes;
    int64_t window = 0;
  };
  struct Missing {
    Clock::time_point asked{};  // epoch: not asked yet
    Clock::time_point first_missed{};
    double backoff = 0.0;
  };
  // What we know of one sender name's sequence numbers.
  struct Peer {
    int64_t highest = -1;
    std::map<int64_t, Missing> missing;
  };

  cosim_msgs::header_t make_header(const Stamp& stamp, const std::string& sender);
  template <class Message>
  void publish_sequenced(const std::string& channel, const Message& message);
  template <class Message>
  void publish_unsequenced(const std::string& channel, const Message& message);
  void send_raw(const std::string& channel, const std::vector<uint8_t>& bytes);
  void send_beacon_locked();
  void beacon_if_due();
  double backoff_cap() const;
  void request_missing();

  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  bool check_run(const cosim_msgs::header_t& header);
  // A window, status or field message of this run from another participant (drop_next's target).
  bool carries_partner_data(const lcm::ReceiveBuffer* buffer, const std::string& channel) const;
  bool accept_sequenced(const cosim_msgs::header_t& header);
  void on_status(cosim_msgs::status_t status, bool fresh);
  void on_field(const cosim_msgs::field_chunk_t& chunk);
  void on_resend(const cosim_msgs::resend_request_t& request);
  void on_beacon(const cosim_msgs::beacon_t& beacon);
  void note_missing(Peer& peer, int64_t from, int64_t to);
  void rtt_sample(double seconds);

  BusOptions options_;
  lcm::LCM lcm_;
  std::unique_ptr<EventRecorder> recorder_;
  int64_t schema_hash_;

  // Publishing side, shared with the heartbeat thread.
  mutable std::mutex publish_mutex_;
  std::condition_variable beacon_cv_;
  std::map<std::string, int64_t> next_sequence_;
  std::map<std::string, std::map<int64_t, Cached>> cache_;
  std::map<FieldKey, std::vector<int64_t>> field_sequences_;  // which cached messages carry it
  Clock::time_point next_beacon_ = Clock::time_point::max();
  double beacon_step_ = 0.0;
  Clock::time_point last_asked_of_us_{};  // last resend request a partner sent us
  bool woken_ = false;

  // Receiving side (main thread only).
  std::set<std::string> own_names_;
  std::map<std::string, Peer> peers_;
  std::map<std::string, Clock::time_point> last_heard_;
  std::deque<cosim_msgs::window_t> windows_;
  std::deque<cosim_msgs::status_t> statuses_;
  std::map<FieldKey, Assembly> assemblies_;
  std::map<FieldKey, std::vector<double>> completed_;
  std::mt19937_64 loss_random_;
  Counters counters_;
  mutable std::mutex counters_mutex_;
  bool accepted_since_poll_ = false;
  int drop_next_ = 0;
  bool missing_pending_ = false;
  Clock::time_point next_request_ = Clock::time_point::max();
  double srtt_ = 0.5e-3;
  double rttvar_ = 0.25e-3;
  std::atomic<double> rto_{1.5e-3};  // read by the heartbeat thread for beacons
};

}  // namespace cosim::coupler
