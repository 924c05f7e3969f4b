// A full disk while a run writes: the event log writer keeps the first error (file and cause)
// instead of throwing inside LCM's callback or losing it at close, and a whole `cosim run` on a
// tiny file system names the file and "No space left on device" and leaves no temporary file.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <vector>

#include "command.hpp"
#include "cosim/coupler/bus.hpp"
#include "cosim/coupler/event_log.hpp"
#include "cosim_msgs/window_t.hpp"

namespace cosim::testing {
namespace {

std::vector<uint8_t> window_message(int64_t sequence) {
  cosim_msgs::window_t window;
  window.header.run_id = 1;
  window.header.sender = "coupler";
  window.header.sequence = sequence;
  window.header.window = sequence;
  window.command = cosim_msgs::window_t::COMMAND_ADVANCE;
  window.reason = std::string(200, 'r');
  window.window_count = 0;
  window.checkpoint_count = 0;
  std::vector<uint8_t> bytes(static_cast<std::size_t>(window.getEncodedSize()));
  window.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

TEST(EventLogWrites, AFullDiskIsKeptWithTheFileAndTheCause) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  coupler::EventRecorder recorder("/dev/full", coupler::RecordMode::all);
  // Far more than the stream's buffer, so writes fail while recording, not only at close.
  for (int64_t sequence = 0; sequence < 500; ++sequence) {
    const auto bytes = window_message(sequence);
    EXPECT_NO_THROW(recorder.record(coupler::kWindowChannel, bytes.data(), bytes.size(), 0));
  }
  recorder.close();
  EXPECT_EQ(recorder.error(), "cannot write the event log /dev/full: No space left on device");
  EXPECT_EQ(coupler::EventRecorder::write_failure("/dev/full"), recorder.error());
}

TEST(EventLogWrites, AFailureAtCloseIsNotLost) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  coupler::EventRecorder recorder("/dev/full", coupler::RecordMode::all);
  const auto bytes = window_message(0);  // stays in the stream's buffer until close
  recorder.record(coupler::kWindowChannel, bytes.data(), bytes.size(), 0);
  EXPECT_EQ(recorder.error(), "");
  recorder.close();
  EXPECT_EQ(recorder.error(), "cannot write the event log /dev/full: No space left on device");
}

// The run folder on a file system of a few kilobytes (a tmpfs in a user and mount namespace of
// its own, no root needed): whatever fills it first, cosim says which file and why.
TEST(DiskFull, ARunOnAFullFileSystemNamesTheFileAndTheCause) {
  if (run_command("unshare -rm true").exit_code != 0) GTEST_SKIP() << "no user namespaces";
  const auto mount_point = fresh_folder("disk-full");
  const auto bin = std::filesystem::read_symlink("/proc/self/exe").parent_path();
  const std::string inner = fmt::format(
      "mount -t tmpfs -o size=8k none {0} && {1}/cosim run {2} --runs-dir {0} --quiet; "
      "echo exit=\\$?; echo leftovers:; find {0} -name '*.tmp'",
      mount_point.string(), bin.string(), test_scene("blade").string());
  const auto result = run_command(fmt::format("unshare -rm sh -c \"{}\"", inner), 60);
  EXPECT_NE(result.output.find("No space left on device"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("cannot write '" + mount_point.string()), std::string::npos)
      << result.output;
  EXPECT_EQ(result.output.find("exit=0"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("exit=1"), std::string::npos) << result.output;
  const auto leftovers = result.output.substr(result.output.find("leftovers:"));
  EXPECT_EQ(leftovers.find(".tmp"), std::string::npos) << result.output;
}

}  // namespace
}  // namespace cosim::testing
