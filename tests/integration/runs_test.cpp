// End-to-end runs of the blade scene through `cosim`: outputs, lossy networks, dying and hung
// solvers, concurrent runs and replay.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <functional>
#include <future>
#include <regex>
#include <sstream>
#include <thread>

#include "command.hpp"
#include "cosim/output/point_series.hpp"
#include "cosim/replay/recording.hpp"
#include "cosim/scenario/section.hpp"

namespace cosim::testing {
namespace {

std::string blade() {
  return test_scene("blade").string();
}

TEST(Runs, BladeRunWritesEveryOutputOfARunFolder) {
  const auto runs = fresh_folder("outputs");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const auto run_dir = run_folder_of(result);
  ASSERT_FALSE(run_dir.empty()) << result.output;
  for (const char* file :
       {"scenario.yaml", "events.lcmlog.zst", "summary.json", "logs/vegetation_beam.log",
        "logs/prescribed_flow.log", "vegetation_beam/plants.h5", "vegetation_beam/plants.xmf"}) {
    EXPECT_TRUE(std::filesystem::exists(run_dir / file)) << file;
  }
  const auto summary = read_summary(run_dir);
  EXPECT_TRUE(summary["ok"].get<bool>());
  EXPECT_EQ(summary["windows_completed"].get<int>(), 20);
  EXPECT_NEAR(summary["simulated_time"].get<double>(), 0.02, 1e-12);
  ASSERT_EQ(summary["participants"].size(), 2u);
  for (const auto& participant : summary["participants"]) {
    EXPECT_EQ(participant["windows"].get<int>(), 21) << participant.dump();  // window 0 included
    EXPECT_GE(participant["compute_seconds"].get<double>(), 0.0);
    EXPECT_GE(participant["coupling_wait_seconds"].get<double>(), 0.0);
    // CPU time of the process: positive, and a solver that mostly waits uses less than its wall.
    EXPECT_GT(participant["cpu_seconds"].get<double>(), 0.0) << participant.dump();
  }
  const auto& beam = summary["participants"][1];
  EXPECT_EQ(beam["name"], "vegetation_beam");
  EXPECT_GT(beam["steps"].get<int64_t>(), 20) << "the beam sub-cycles inside each window";
  const double tip = beam["report"]["metrics"]["tip_streamwise_position"]["value"].get<double>();
  EXPECT_GT(tip, 0.0) << "the stream bends the blade downstream";
  // Every default is written into the resolved scenario.
  const auto resolved = scenario::load_yaml_file(run_dir / "scenario.yaml");
  EXPECT_TRUE(resolved["coupling"]["resend_interval"]);
  EXPECT_TRUE(resolved["participants"]["vegetation_beam"]["added_mass_coefficient"]);
  // Frames at the output interval (0, 5, 10, 15, 20 ms).
  EXPECT_EQ(output::count_point_frames(run_dir / "vegetation_beam/plants.h5"), 5);
}

std::map<std::pair<int64_t, std::string>, std::vector<double>> beam_fields(
    const std::filesystem::path& run_dir) {
  std::map<std::pair<int64_t, std::string>, std::vector<double>> fields;
  const auto recording = replay::read_recording(run_dir / "events.lcmlog.zst", "vegetation_beam");
  for (const auto& [window, recorded] : recording.windows) {
    for (const auto& [field, values] : recorded.fields) fields[{window.window, field}] = values;
  }
  return fields;
}

TEST(Runs, TenPercentMessageLossGivesTheSameResultAsNoLoss) {
  const auto runs = fresh_folder("loss");
  const auto clean = run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(clean.exit_code, 0) << clean.output;
  const auto lossy = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet --inject-loss 0.1", blade(), runs.string()));
  ASSERT_EQ(lossy.exit_code, 0) << lossy.output;
  const auto lossy_summary = read_summary(run_folder_of(lossy));
  EXPECT_GT(lossy_summary["traffic"]["dropped_injected"].get<int64_t>(), 10)
      << "loss was really injected";
  const auto expected = beam_fields(run_folder_of(clean));
  const auto actual = beam_fields(run_folder_of(lossy));
  ASSERT_EQ(expected.size(), actual.size());
  ASSERT_EQ(expected.size(), 21u * 3u);  // positions, velocities, drag for windows 0..20
  for (const auto& [key, values] : expected) {
    ASSERT_TRUE(actual.contains(key));
    EXPECT_EQ(values, actual.at(key)) << "window " << key.first << " field " << key.second;
  }
}

// Two hosts: the blade runs in a second network namespace joined to the coupler's by a veth link
// (two_hosts.sh), started there with the `cosim join` line the run printed.
TEST(Runs, AParticipantOnAnotherHostGivesTheSameResultAsOnOneHost) {
  const auto runs = fresh_folder("two_hosts");
  const auto one_host =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(one_host.exit_code, 0) << one_host.output;
  const auto two_hosts = run_command(fmt::format("./two_hosts.sh {} {} {} vegetation_beam",
                                                 bin_dir().string(), blade(), runs.string()),
                                     180);
  if (two_hosts.exit_code == 77) GTEST_SKIP() << two_hosts.output;
  ASSERT_EQ(two_hosts.exit_code, 0) << two_hosts.output;
  EXPECT_NE(two_hosts.output.find("cosim: start 'vegetation_beam' on its host now"),
            std::string::npos)
      << two_hosts.output;
  const auto run_dir = run_folder_of(two_hosts);
  const auto summary = read_summary(run_dir);
  EXPECT_EQ(summary["remote_participants"], nlohmann::json::array({"vegetation_beam"}));
  EXPECT_NE(summary["lcm_url"].get<std::string>().find("ttl=1"), std::string::npos);
  // The remote participant wrote its outputs where the join line said (a shared folder here).
  EXPECT_EQ(output::count_point_frames(run_dir / "vegetation_beam/plants.h5"), 5);
  const auto expected = beam_fields(run_folder_of(one_host));
  const auto actual = beam_fields(run_dir);
  ASSERT_EQ(expected.size(), 21u * 3u);
  ASSERT_EQ(expected.size(), actual.size());
  for (const auto& [key, values] : expected) {
    ASSERT_TRUE(actual.contains(key));
    EXPECT_EQ(values, actual.at(key)) << "window " << key.first << " field " << key.second;
  }
}

TEST(Runs, ARemoteParticipantIsCheckedBeforeAnythingStarts) {
  const auto runs = fresh_folder("remote_refused");
  auto expect_refused = [&](const std::string& options, const std::string& message) {
    const auto refused =
        run_cosim(fmt::format("run {} --runs-dir {} --quiet {}", blade(), runs.string(), options));
    EXPECT_EQ(refused.exit_code, 2) << options;
    EXPECT_NE(refused.output.find(message), std::string::npos) << refused.output;
  };
  expect_refused("--remote nobody",
                 "--remote 'nobody': this scene runs no participant 'nobody' (it runs "
                 "prescribed_flow, vegetation_beam)");
  expect_refused("--remote vegetation_beam --network private",
                 "--network private cannot be combined with --remote");
  expect_refused("--remote vegetation_beam --fault vegetation_beam:exit@3",
                 "a fault can only be injected into a process this command starts");
  EXPECT_TRUE(std::filesystem::is_empty(runs)) << "no run folder for a refused run";
  // Nobody types the join line: the run names the participant it waited for.
  const auto never_joined = run_cosim(
      fmt::format("run {} --runs-dir {} --quiet --remote vegetation_beam --startup-timeout 1",
                  blade(), runs.string()));
  EXPECT_EQ(never_joined.exit_code, 1);
  EXPECT_NE(never_joined.output.find("participant(s) vegetation_beam did not start within 1 s"),
            std::string::npos)
      << never_joined.output;
}

TEST(Runs, ASolverThatDiesIsNamedWithItsWindowWithinSeconds) {
  const auto runs = fresh_folder("exit");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet --fault vegetation_beam:exit@5", blade(),
                            runs.string()),
                60);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_LT(result.seconds, 10.0);
  const auto summary = read_summary(run_folder_of(result));
  ASSERT_FALSE(summary.empty()) << result.output;
  const std::string failure = summary["failure"].get<std::string>();
  EXPECT_NE(failure.find("vegetation_beam"), std::string::npos) << failure;
  EXPECT_NE(failure.find("window 5"), std::string::npos) << failure;
  EXPECT_NE(result.output.find("FAILED"), std::string::npos);
}

TEST(Runs, ASolverThatHangsIsNamedWithItsWindowWithinTheTimeout) {
  const auto runs = fresh_folder("hang");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet --fault vegetation_beam:hang@7", blade(),
                            runs.string()),
                60);
  EXPECT_NE(result.exit_code, 0);
  EXPECT_LT(result.seconds, 15.0) << "the scene's timeout is 2 s";
  const auto summary = read_summary(run_folder_of(result));
  ASSERT_FALSE(summary.empty()) << result.output;
  const std::string failure = summary["failure"].get<std::string>();
  EXPECT_NE(failure.find("vegetation_beam"), std::string::npos) << failure;
  EXPECT_NE(failure.find("window 7"), std::string::npos) << failure;
}

TEST(Runs, ASolverErrorIsReportedWithItsMessage) {
  const auto runs = fresh_folder("throw");
  const auto result =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet --fault prescribed_flow:throw@3", blade(),
                            runs.string()),
                60);
  EXPECT_NE(result.exit_code, 0);
  const auto summary = read_summary(run_folder_of(result));
  ASSERT_FALSE(summary.empty()) << result.output;
  const std::string failure = summary["failure"].get<std::string>();
  EXPECT_NE(failure.find("prescribed_flow"), std::string::npos) << failure;
  EXPECT_NE(failure.find("window 3"), std::string::npos) << failure;
  EXPECT_NE(failure.find("injected fault"), std::string::npos) << failure;
}

TEST(Runs, ConcurrentRunsDoNotHearEachOther) {
  const auto runs = fresh_folder("concurrent");
  std::vector<std::future<CommandResult>> started;
  for (int i = 0; i < 3; ++i) {
    started.push_back(std::async(std::launch::async, [&] {
      return run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
    }));
  }
  std::vector<std::filesystem::path> folders;
  for (auto& run : started) {
    const auto result = run.get();
    ASSERT_EQ(result.exit_code, 0) << result.output;
    folders.push_back(run_folder_of(result));
  }
  ASSERT_NE(folders[0], folders[1]);
  for (const auto& folder : folders) {
    const auto summary = read_summary(folder);
    EXPECT_EQ(summary["traffic"]["dropped_foreign"].get<int64_t>(), 0) << folder;
  }
  EXPECT_EQ(beam_fields(folders[0]), beam_fields(folders[1]));
  EXPECT_EQ(beam_fields(folders[0]), beam_fields(folders[2]));
}

TEST(Runs, ReplayDrivesTheBeamBitForBit) {
  const auto runs = fresh_folder("replay");
  const auto recorded =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(recorded.exit_code, 0) << recorded.output;
  const auto run_dir = run_folder_of(recorded);
  const auto replayed =
      run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                            run_dir.string(), runs.string()));
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("IDENTICAL"), std::string::npos) << replayed.output;
  EXPECT_NE(replayed.output.find("63 fields"), std::string::npos) << replayed.output;
  EXPECT_NE(replayed.output.find("1 output files"), std::string::npos) << replayed.output;
}

// Records a blade run, edits its resolved scenario with `edit`, and replays the beam against it.
CommandResult replay_edited_blade(const std::string& label,
                                  const std::function<void(YAML::Node&)>& edit) {
  const auto runs = fresh_folder(label);
  const auto recorded =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  EXPECT_EQ(recorded.exit_code, 0) << recorded.output;
  const auto run_dir = run_folder_of(recorded);
  const auto scenario_file = run_dir / "scenario.yaml";
  auto document = scenario::load_yaml_file(scenario_file);
  edit(document);
  {
    std::ofstream out(scenario_file);
    out << document;
  }
  return run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                               run_dir.string(), runs.string()));
}

TEST(Runs, ReplayDetectsADifferentSolver) {
  // Change the beam's physics in the recorded scenario: the replay must notice.
  const auto replayed = replay_edited_blade("replay-diff", [](YAML::Node& document) {
    document["participants"]["vegetation_beam"]["drag_coefficient"] = 1.0;
  });
  EXPECT_EQ(replayed.exit_code, 1) << replayed.output;
  EXPECT_NE(replayed.output.find("DIFFERENT"), std::string::npos) << replayed.output;
}

// One world: a recorded flow replayed into a scene whose world is tilted no longer shares the
// beam's gravity. The coupler refuses at the handshake, naming both participants.
TEST(Runs, ReplayIntoAnotherWorldIsRefusedAtTheHandshake) {
  const auto replayed = replay_edited_blade("replay-world", [](YAML::Node& document) {
    document["world"] = YAML::Load("{slope_degrees: 5}");
  });
  EXPECT_NE(replayed.exit_code, 0) << replayed.output;
  EXPECT_NE(replayed.output.find("participants disagree on the world"), std::string::npos)
      << replayed.output;
  EXPECT_NE(replayed.output.find("'vegetation_beam' declares gravity (0.854998"), std::string::npos)
      << replayed.output;
  EXPECT_NE(replayed.output.find("'prescribed_flow' declares (0, 0, -9.81)"), std::string::npos)
      << replayed.output;
}

// The children of `parent`, from /proc.
std::vector<pid_t> children_of(pid_t parent) {
  std::vector<pid_t> children;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "stat");
    std::string stat;
    std::getline(in, stat);
    // pid (comm) state ppid ...: comm may hold spaces, so read after its closing parenthesis.
    const auto close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(stat.substr(close + 2));
    char state = 0;
    pid_t ppid = 0;
    rest >> state >> ppid;
    if (ppid == parent) children.push_back(std::stoi(name));
  }
  return children;
}

bool alive(pid_t pid) {
  std::ifstream in(fmt::format("/proc/{}/stat", pid));
  std::string stat;
  if (!std::getline(in, stat)) return false;
  const auto close = stat.rfind(')');
  return close != std::string::npos && stat.size() > close + 2 && stat[close + 2] != 'Z';
}

struct Interrupted {
  int exit_code = -1;
  std::string output;
  std::vector<pid_t> children;
};

// Starts `cosim run` on the blade, waits until its windows run, sends `signal`, and waits for
// cosim to end (at most 30 s).
Interrupted interrupt_blade(const std::filesystem::path& runs, const std::string& options,
                            int signal, const std::string& ready_text = "] window ",
                            const std::string& ready_file = "cosim.out") {
  Interrupted interrupted;
  const auto output_file = runs / "cosim.out";
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, STDOUT_FILENO);
    dup2(fd, STDERR_FILENO);
    // The test executables are built beside cosim.
    const auto bin = std::filesystem::read_symlink("/proc/self/exe").parent_path();
    const std::string command =
        fmt::format("exec {}/cosim run {} --runs-dir {} --progress-interval 0.2 {}", bin.string(),
                    blade(), runs.string(), options);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Running: `ready_text` shows in `ready_file` (in `runs` or in a run folder there); the
  // progress lines show windows every 0.2 s.
  auto ready = [&] {
    std::vector<std::filesystem::path> files{runs / ready_file};
    for (const auto& entry : std::filesystem::directory_iterator(runs)) {
      if (entry.is_directory()) files.push_back(entry.path() / ready_file);
    }
    for (const auto& file : files) {
      std::ifstream in(file);
      const std::string text{std::istreambuf_iterator<char>(in), {}};
      if (text.find(ready_text) != std::string::npos) return true;
    }
    return false;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline && !ready()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  interrupted.children = children_of(pid);
  kill(pid, signal);
  int status = 0;
  for (int i = 0; i < 300 && waitpid(pid, &status, WNOHANG) == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (waitpid(pid, &status, WNOHANG) == 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  interrupted.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::ifstream in(output_file);
  interrupted.output.assign(std::istreambuf_iterator<char>(in), {});
  return interrupted;
}

void expect_clean_interruption(const Interrupted& run, const std::string& signal, int exit_code,
                               const std::string& total) {
  EXPECT_EQ(run.exit_code, exit_code) << run.output;
  EXPECT_EQ(run.children.size(), 2u) << "both solvers were running when the signal came";
  for (const pid_t child : run.children) EXPECT_FALSE(alive(child)) << "orphan " << child;
  const std::string line = "interrupted by " + signal + " at window ";
  EXPECT_NE(run.output.find("cosim: " + line), std::string::npos) << run.output;
  CommandResult printed;
  printed.output = run.output;
  const auto run_dir = run_folder_of(printed);
  ASSERT_FALSE(run_dir.empty()) << run.output;
  const auto summary = read_summary(run_dir);
  ASSERT_FALSE(summary.empty()) << run.output;
  EXPECT_FALSE(summary["ok"].get<bool>());
  const std::string failure = summary["failure"].get<std::string>();
  EXPECT_EQ(failure.rfind(line, 0), 0u) << failure;
  EXPECT_NE(failure.find(" of " + total), std::string::npos) << failure;
  EXPECT_EQ(summary["interrupted_by"], signal);
}

TEST(Runs, SigintStopsEveryProcessAndRecordsTheInterruption) {
  const auto runs = fresh_folder("sigint");
  // Long enough to be running when the signal comes: 30000 windows.
  const auto run = interrupt_blade(runs, "--set duration=30", SIGINT);
  expect_clean_interruption(run, "SIGINT", 130, "30000");
}

TEST(Runs, SigtermStopsEvenAStoppedSolver) {
  const auto runs = fresh_folder("sigterm");
  // The beam stops itself (SIGSTOP) in window 5 and would wait out a 60 s timeout: SIGTERM to
  // cosim must still end everything at once, the stopped process included.
  const auto run =
      interrupt_blade(runs, "--fault vegetation_beam:hang@5 --set coupling.timeout=60", SIGTERM,
                      "injected fault: hanging in window 5", "logs/vegetation_beam.log");
  expect_clean_interruption(run, "SIGTERM", 143, "20");
  CommandResult printed;
  printed.output = run.output;
  const auto summary = read_summary(run_folder_of(printed));
  EXPECT_EQ(summary["failure"], "interrupted by SIGTERM at window 5 of 20") << run.output;
}

// A recorded run whose beam outputs are gone: the replay must not call it identical.
TEST(Runs, ReplayRefusesWhenTheRecordedOutputsAreMissing) {
  const auto runs = fresh_folder("replay-missing");
  const auto recorded =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(recorded.exit_code, 0) << recorded.output;
  const auto run_dir = run_folder_of(recorded);
  std::filesystem::remove(run_dir / "vegetation_beam/plants.h5");
  const auto replayed =
      run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                            run_dir.string(), runs.string()));
  EXPECT_EQ(replayed.exit_code, 1) << replayed.output;
  EXPECT_EQ(replayed.output.find("IDENTICAL"), std::string::npos) << replayed.output;
  EXPECT_NE(replayed.output.find("plants.h5: missing from the recorded run"), std::string::npos)
      << replayed.output;
}

// Byte offset of record `index` of an LCM log (28-byte headers, big-endian lengths).
std::size_t record_offset(const std::string& log, int index) {
  std::size_t offset = 0;
  auto be32 = [&](std::size_t at) {
    return (uint32_t(uint8_t(log[at])) << 24) | (uint32_t(uint8_t(log[at + 1])) << 16) |
           (uint32_t(uint8_t(log[at + 2])) << 8) | uint32_t(uint8_t(log[at + 3]));
  };
  for (int i = 0; i < index; ++i) offset += 28 + be32(offset + 20) + be32(offset + 24);
  return offset;
}

TEST(Runs, ReplayNamesTheDamageOfACorruptedOrTruncatedLog) {
  const auto runs = fresh_folder("replay-damaged");
  const auto recorded =
      run_cosim(fmt::format("run {} --runs-dir {} --quiet", blade(), runs.string()));
  ASSERT_EQ(recorded.exit_code, 0) << recorded.output;
  const auto run_dir = run_folder_of(recorded);
  const auto compressed = run_dir / "events.lcmlog.zst";
  std::string packed;
  {
    std::ifstream in(compressed, std::ios::binary);
    packed.assign(std::istreambuf_iterator<char>(in), {});
  }
  // Compressed: a flipped byte fails its block's checksum, a cut file names the cut.
  auto replay_compressed = [&](const std::string& bytes) {
    std::ofstream(compressed, std::ios::binary | std::ios::trunc) << bytes;
    return run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                                 run_dir.string(), runs.string()));
  };
  std::string flipped = packed;
  flipped[packed.size() / 3] = static_cast<char>(flipped[packed.size() / 3] ^ 0x5a);
  const auto corrupt = replay_compressed(flipped);
  EXPECT_NE(corrupt.exit_code, 0);
  EXPECT_NE(corrupt.output.find("events.lcmlog.zst is damaged at byte"), std::string::npos)
      << corrupt.output;
  const auto cut = replay_compressed(packed.substr(0, packed.size() / 2));
  EXPECT_NE(cut.exit_code, 0);
  EXPECT_NE(cut.output.find("cut short"), std::string::npos) << cut.output;
  std::ofstream(compressed, std::ios::binary | std::ios::trunc) << packed;
  // Plain (an older run, or one exported with `cosim export-log`): the record-by-record reader
  // names byte and record.
  const auto exported = run_cosim(fmt::format("export-log {}", run_dir.string()));
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const auto log_file = run_dir / "events.lcmlog";
  std::string log;
  {
    std::ifstream in(log_file, std::ios::binary);
    log.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_GT(log.size(), 0u) << exported.output;
  std::filesystem::remove(compressed);
  auto replay_with = [&](const std::string& bytes) {
    std::ofstream(log_file, std::ios::binary | std::ios::trunc) << bytes;
    return run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                                 run_dir.string(), runs.string()));
  };
  const std::size_t at = record_offset(log, 40);
  std::string corrupted = log;
  corrupted.replace(at, 4, "JUNK");
  const auto damaged = replay_with(corrupted);
  EXPECT_NE(damaged.exit_code, 0);
  EXPECT_NE(damaged.output.find(fmt::format(
                "events.lcmlog is damaged at byte {} (record 40): expected the record marker "
                "0xEDA1DA01, found 0x4A554E4B",
                at)),
            std::string::npos)
      << damaged.output;
  const auto truncated = replay_with(log.substr(0, log.size() - 10));
  EXPECT_NE(truncated.exit_code, 0);
  EXPECT_NE(truncated.output.find("(truncated)"), std::string::npos) << truncated.output;
  EXPECT_EQ(truncated.output.find("is not in the recording"), std::string::npos)
      << truncated.output;
}

// A run whose blade exits in window 5 is replayed over the windows it completed. Which window
// the coupler last saw whole (3 or 4) depends on timing, as windows are granted two ahead: the
// replay must cover exactly that many (windows 0..N) and match them bit for bit.
TEST(Runs, AFailedRunIsReplayedUpToItsLastWholeWindow) {
  const auto runs = fresh_folder("replay-failed");
  const auto recorded = run_cosim(fmt::format(
      "run {} --runs-dir {} --quiet --fault vegetation_beam:exit@5", blade(), runs.string()));
  ASSERT_EQ(recorded.exit_code, 1) << recorded.output;
  const auto replayed =
      run_cosim(fmt::format("replay {} --participant vegetation_beam --runs-dir {} --quiet",
                            run_folder_of(recorded).string(), runs.string()));
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  const std::regex pattern(
      R"(up to window (\d+) of 20 \(the recorded run failed: .*\): (\d+) windows, )");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(replayed.output, match, pattern)) << replayed.output;
  const int last_whole = std::stoi(match[1]);
  EXPECT_TRUE(last_whole == 3 || last_whole == 4) << replayed.output;
  EXPECT_EQ(std::stoi(match[2]), last_whole + 1) << replayed.output;
  EXPECT_NE(replayed.output.find("IDENTICAL"), std::string::npos) << replayed.output;
}
}  // namespace
}  // namespace cosim::testing

namespace cosim::testing {
namespace {

TEST(Runs, SweepTabulatesEveryMetricPerValue) {
  const auto runs = fresh_folder("sweep");
  const auto result = run_cosim(fmt::format(
      "sweep {} --vary participants.vegetation_beam.plants.0.links --values 4 8 --runs-dir {} "
      "--quiet",
      blade(), runs.string()));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::filesystem::path table;
  for (const auto& entry : std::filesystem::directory_iterator(runs)) {
    if (entry.path().extension() == ".csv") table = entry.path();
  }
  ASSERT_FALSE(table.empty()) << result.output;
  std::ifstream in(table);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("participants.vegetation_beam.plants.0.links,ok,wall_seconds,metric", 0),
            0u);
  int rows = 0, tip_rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    tip_rows += line.find("vegetation_beam.tip_streamwise_position") != std::string::npos;
  }
  EXPECT_EQ(tip_rows, 2) << "one row per value";
  EXPECT_EQ(rows, 4) << "two metrics of the beam for each of two values";
}

}  // namespace
}  // namespace cosim::testing
