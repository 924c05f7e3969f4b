// Transport: chunked fields survive heavy loss through retransmission, foreign runs and
// duplicates are dropped, and a silent partner gives a named error instead of a hang.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <numeric>
#include <thread>

#include "cosim/coupler/bus.hpp"
#include "cosim/coupler/participant.hpp"

namespace cosim::coupler {
namespace {

BusOptions options(const std::string& name, int64_t run_id, double loss = 0.0) {
  BusOptions bus;
  bus.url = run_lcm_url(4242);
  bus.run_id = run_id;
  bus.name = name;
  bus.chunk_values = 16;
  bus.loss_probability = loss;
  bus.loss_seed = 99;
  return bus;
}

std::vector<double> pattern(int count) {
  std::vector<double> values(count);
  for (int i = 0; i < count; ++i) values[i] = std::sin(0.37 * i) * 1e3 + 1.0 / (i + 3);
  return values;
}

// Receives `key` on `receiver`, asking `sender`'s bus for missing chunks like a participant.
std::optional<std::vector<double>> receive_with_resends(Bus& receiver, Bus& sender,
                                                        const FieldKey& key, double seconds) {
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() < seconds) {
    if (auto values = receiver.field_values(key)) return values;
    receiver.request_resend(key, receiver.missing_chunks(key));
    for (int i = 0; i < 5; ++i) {
      sender.poll(0.002);
      receiver.poll(0.002);
    }
  }
  return std::nullopt;
}

TEST(Bus, ChunkedFieldSurvivesThirtyPercentLossBitExact) {
  Bus sender(options("sender", 7));
  Bus receiver(options("receiver", 7, 0.3));
  const auto values = pattern(1000);  // 63 chunks of 16
  sender.publish_field(Stamp{3, 0.1, 0.01}, "positions", values);
  const auto received = receive_with_resends(receiver, sender, {"sender", 3, "positions"}, 10.0);
  ASSERT_TRUE(received.has_value());
  ASSERT_EQ(received->size(), values.size());
  EXPECT_EQ(std::memcmp(received->data(), values.data(), values.size() * sizeof(double)), 0);
  const auto counters = receiver.counters();
  EXPECT_GT(counters.dropped_injected, 0);
  EXPECT_GT(counters.resends_requested, 0);
  EXPECT_GT(sender.counters().resends_served, 0);
}

TEST(Bus, EmptyFieldIsDelivered) {
  Bus sender(options("sender", 8));
  Bus receiver(options("receiver", 8));
  sender.publish_field(Stamp{1, 0.0, 0.0}, "drag", std::vector<double>{});
  const auto received = receive_with_resends(receiver, sender, {"sender", 1, "drag"}, 5.0);
  ASSERT_TRUE(received.has_value());
  EXPECT_TRUE(received->empty());
}

TEST(Bus, ForeignRunsAreIgnored) {
  Bus other_run(options("sender", 1001));
  Bus receiver(options("receiver", 1002));
  other_run.publish_field(Stamp{1, 0.0, 0.0}, "positions", pattern(10));
  for (int i = 0; i < 20; ++i) receiver.poll(0.005);
  EXPECT_FALSE(receiver.has_field({"sender", 1, "positions"}));
  EXPECT_GT(receiver.counters().dropped_foreign, 0);
}

TEST(Bus, RunUrlsDifferPerRun) {
  EXPECT_NE(run_lcm_url(1), run_lcm_url(2));
  EXPECT_EQ(run_lcm_url(5), run_lcm_url(5));
}

TEST(Participant, SilentPartnerIsNamedWithFieldAndWindow) {
  ParticipantOptions participant;
  participant.name = "vegetation_beam";
  participant.url = run_lcm_url(777);
  participant.run_id = 777;
  participant.timeout = 0.5;
  Participant waiting(participant);
  const auto start = std::chrono::steady_clock::now();
  try {
    waiting.receive("fluid_mps", "ambient_velocity@vegetation_beam", 12);
    FAIL() << "a silent partner must not hang the receiver";
  } catch (const CouplingError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("fluid_mps"), std::string::npos) << message;
    EXPECT_NE(message.find("ambient_velocity@vegetation_beam"), std::string::npos) << message;
    EXPECT_NE(message.find("window 12"), std::string::npos) << message;
  }
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(waited, 3.0);
}

TEST(Participant, SilentCouplerIsReported) {
  ParticipantOptions participant;
  participant.name = "debris_dem";
  participant.url = run_lcm_url(778);
  participant.run_id = 778;
  participant.timeout = 0.5;
  Participant waiting(participant);
  EXPECT_THROW(waiting.next_window(), CouplingError);
}

}  // namespace
}  // namespace cosim::coupler
