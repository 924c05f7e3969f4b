// The transport under the participant API and the coupler: LCM publish/receive with message
// headers, run isolation, duplicate dropping, chunked float64 fields with retransmission on
// request, optional recording of all traffic to an LCM event log, and optional injected loss
// (for tests that prove a lossy network never changes a result).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <chrono>
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

#include "cosim_msgs/field_chunk_t.hpp"
#include "cosim_msgs/resend_request_t.hpp"
#include "cosim_msgs/status_t.hpp"
#include "cosim_msgs/window_t.hpp"

namespace cosim::coupler {

inline constexpr const char* kWindowChannel = "COSIM_WINDOW";
inline constexpr const char* kStatusChannel = "COSIM_STATUS";
inline constexpr const char* kFieldChannel = "COSIM_FIELD";
inline constexpr const char* kResendChannel = "COSIM_RESEND";

// Hash over every message type of the protocol: peers built from other .lcm files disagree.
int64_t protocol_schema_hash();

// The LCM URL of a run: a port and multicast group derived from the run id, so concurrent runs
// do not hear each other; a large receive buffer because UDP loses big bursts otherwise.
std::string run_lcm_url(int64_t run_id);

struct BusOptions {
  std::string url;
  int64_t run_id = 0;
  std::string name;               // own participant name (sender of what we publish)
  int chunk_values = 4096;        // float64 values per field chunk
  double loss_probability = 0.0;  // injected loss of received messages (tests)
  uint64_t loss_seed = 1;
  std::filesystem::path record_log;  // when set, every message heard is written here
  int cached_windows = 4;            // windows of own fields kept for retransmission
};

// Who, when and where a message belongs, as stamped into its header.
struct Stamp {
  int64_t window = 0;
  double sim_time = 0.0;
  double dt = 0.0;
};

struct FieldKey {
  std::string sender;
  int64_t window;
  std::string field;
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
  void publish_window(const Stamp& stamp, int8_t command, int64_t total_windows,
                      const std::string& reason = "");
  void publish_status(const Stamp& stamp, cosim_msgs::status_t status);
  // Splits values into chunks and keeps them for retransmission. `as_sender` lets a replay
  // driver publish under the recorded participant's name.
  void publish_field(const Stamp& stamp, const std::string& field, std::span<const double> values,
                     const std::string& as_sender = "");
  void request_resend(const FieldKey& key, const std::vector<int32_t>& missing_chunks);

  // Receives for up to `seconds` (at least one LCM handle call); returns true if any message
  // was accepted. Resend requests aimed at us are answered here.
  bool poll(double seconds);

  // Received messages, oldest first; the caller pops what it consumes.
  std::deque<cosim_msgs::window_t>& windows() { return windows_; }
  std::deque<cosim_msgs::status_t>& statuses() { return statuses_; }

  // A complete field, or nothing yet. Missing chunks can be listed for a resend request.
  std::optional<std::vector<double>> field_values(const FieldKey& key);
  bool has_field(const FieldKey& key) const;
  std::vector<int32_t> missing_chunks(const FieldKey& key) const;  // empty list: nothing heard
  // Every complete field heard, without consuming (replay comparison).
  const std::map<FieldKey, std::vector<double>>& completed_fields() const { return completed_; }
  void forget_fields_before(int64_t window);

  // When we last accepted any message from a sender (steady clock).
  std::optional<std::chrono::steady_clock::time_point> last_heard(const std::string& sender) const;

  // Extra names this bus publishes as and therefore ignores when heard back (replay driver).
  void add_own_name(const std::string& name) { own_names_.insert(name); }

  struct Counters {
    int64_t accepted = 0;
    int64_t dropped_injected = 0;
    int64_t dropped_foreign = 0;
    int64_t dropped_duplicate = 0;
    int64_t resends_served = 0;
    int64_t resends_requested = 0;
  };
  Counters counters() const;

 private:
  struct Assembly {
    int32_t chunk_count = 0;
    int64_t total_values = 0;
    std::vector<double> values;
    std::vector<bool> received;
    int32_t received_count = 0;
  };

  cosim_msgs::header_t make_header(const Stamp& stamp, const std::string& sender);
  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  bool accept_header(const cosim_msgs::header_t& header);
  void on_field(const cosim_msgs::field_chunk_t& chunk);
  void on_resend(const cosim_msgs::resend_request_t& request);
  template <class Message>
  void publish_message(const std::string& channel, const Message& message);

  BusOptions options_;
  lcm::LCM lcm_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t log_event_number_ = 0;
  int64_t schema_hash_;

  mutable std::mutex publish_mutex_;
  std::map<std::string, int64_t> next_sequence_;
  // Own published chunks, for retransmission: key -> chunks.
  std::map<FieldKey, std::vector<cosim_msgs::field_chunk_t>> sent_;

  std::set<std::string> own_names_;
  std::map<std::string, std::set<int64_t>> seen_sequences_;
  std::map<std::string, std::chrono::steady_clock::time_point> last_heard_;
  std::deque<cosim_msgs::window_t> windows_;
  std::deque<cosim_msgs::status_t> statuses_;
  std::map<FieldKey, Assembly> assemblies_;
  std::map<FieldKey, std::vector<double>> completed_;
  std::mt19937_64 loss_random_;
  Counters counters_;
  bool accepted_since_poll_ = false;
};

}  // namespace cosim::coupler
