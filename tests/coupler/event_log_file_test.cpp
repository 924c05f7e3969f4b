// The compressed event log: events come back byte for byte (field chunks through their value
// columns too), the file is a valid zstd stream and exports to a plain LCM log, logs of the
// first format still read, seeking by window uses the index (or the block headers when the index
// is missing), and damage or a full disk is named with the file and byte offset.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <zstd.h>
#include <lcm/lcm-cpp.hpp>

#include <unistd.h>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "cosim/coupler/event_log_file.hpp"
#include "cosim_msgs/field_chunk_t.hpp"

namespace cosim::coupler {
namespace {

namespace fs = std::filesystem;

struct Sample {
  std::string channel;
  std::vector<uint8_t> data;
  int64_t utime, window;
};

// Events like a run's: a window number in front, then doubles that vary smoothly (fields) and
// some noise, so the data compresses as real traffic does, not perfectly.
std::vector<Sample> samples(int windows, int per_window) {
  std::vector<Sample> out;
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 1e-3);
  for (int w = 0; w < windows; ++w) {
    for (int e = 0; e < per_window; ++e) {
      Sample s;
      s.channel = e % 3 == 0 ? "COSIM_STATUS" : "COSIM_FIELD";
      s.window = w;
      s.utime = 1'000'000 + 1000 * w + e;
      std::vector<double> values(200 + 50 * (e % 4));
      for (std::size_t i = 0; i < values.size(); ++i) {
        values[i] = std::sin(0.01 * static_cast<double>(i) + 0.1 * w) + noise(random);
      }
      s.data.resize(8 + values.size() * sizeof(double));
      std::memcpy(s.data.data(), &s.window, 8);
      std::memcpy(s.data.data() + 8, values.data(), values.size() * sizeof(double));
      out.push_back(std::move(s));
    }
  }
  return out;
}

fs::path test_directory() {
  return fs::temp_directory_path() / ("cosim_event_log_" + std::to_string(getpid()));
}

fs::path temporary(const std::string& name) {
  fs::create_directories(test_directory());
  return test_directory() / name;
}

class RemoveTestFiles : public ::testing::Environment {
 public:
  void TearDown() override { fs::remove_all(test_directory()); }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new RemoveTestFiles);

void write_log(const fs::path& file, const std::vector<Sample>& events) {
  EventLogWriter writer(file);
  for (const auto& s : events)
    writer.append(s.channel, s.data.data(), s.data.size(), s.utime, s.window);
  writer.close();
}

int64_t window_of(const LoggedEvent& event) {
  int64_t window = 0;
  std::memcpy(&window, event.data.data(), 8);
  return window;
}

TEST(EventLogFile, EventsComeBackByteForByteInSeveralBlocks) {
  const auto events = samples(120, 12);  // about 3 MB raw
  const fs::path file = temporary("round_trip.lcmlog.zst");
  write_log(file, events);
  EventLogReader reader(file);
  EXPECT_TRUE(reader.compressed());
  for (std::size_t i = 0; i < events.size(); ++i) {
    const auto event = reader.next();
    ASSERT_TRUE(event) << "event " << i << " missing";
    EXPECT_EQ(event->number, static_cast<int64_t>(i));
    EXPECT_EQ(event->timestamp, events[i].utime);
    EXPECT_EQ(event->channel, events[i].channel);
    ASSERT_EQ(event->data, events[i].data) << "event " << i;
  }
  EXPECT_FALSE(reader.next());
  EXPECT_GE(reader.blocks().size(), 3u);
  EXPECT_EQ(reader.blocks().front().first_window, 0);
  EXPECT_EQ(reader.blocks().back().last_window, 119);
}

// Field chunks as solvers send them: two senders, a field split into chunks at two offsets,
// values moving smoothly (a swaying blade) with the low bits of a real computation, plus a
// COSIM_FIELD message that is not a chunk at all.
std::vector<Sample> field_samples(int windows) {
  std::vector<Sample> out;
  const auto add = [&](const std::string& sender, const std::string& field, int64_t offset,
                       int count, int window, double phase) {
    cosim_msgs::field_chunk_t chunk;
    chunk.header.run_id = 42;
    chunk.header.sender = sender;
    chunk.header.sequence = static_cast<int64_t>(out.size());
    chunk.header.window = window;
    chunk.header.sim_time = 5e-4 * window;
    chunk.header.dt = 5e-4;
    chunk.field = field;
    chunk.chunk_index = static_cast<int32_t>(offset / count);
    chunk.chunk_count = 2;
    chunk.total_values = 2 * count;
    chunk.offset = offset;
    chunk.value_count = count;
    for (int i = 0; i < count; ++i) {
      const double s = 0.045 * (i + offset) / (2.0 * count);
      chunk.values.push_back(s * std::sin(0.3 * std::sin(2e-3 * window + phase) * s / 0.045));
    }
    Sample sample{"COSIM_FIELD", std::vector<uint8_t>(chunk.getEncodedSize()), 1000 * window,
                  window};
    chunk.encode(sample.data.data(), 0, static_cast<int>(sample.data.size()));
    out.push_back(std::move(sample));
  };
  for (int w = 0; w < windows; ++w) {
    add("vegetation_beam", "positions", 0, 60, w, 0.0);
    add("vegetation_beam", "positions", 60, 60, w, 0.0);
    add("prescribed_flow", "ambient_velocity@vegetation_beam", 0, 40, w, 1.0);
    if (w % 50 == 0) {
      Sample odd{"COSIM_FIELD", {1, 2, 3, 4, 5, 6, 7, 8, 9}, 1000 * w, w};
      out.push_back(std::move(odd));
    }
  }
  return out;
}

std::vector<uint8_t> plain_lcm_log(const std::vector<Sample>& events) {
  std::vector<uint8_t> out;
  const auto be = [&](uint64_t value, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(value >> (8 * i)));
  };
  for (std::size_t i = 0; i < events.size(); ++i) {
    be(0xEDA1DA01u, 4);
    be(i, 8);
    be(static_cast<uint64_t>(events[i].utime), 8);
    be(events[i].channel.size(), 4);
    be(events[i].data.size(), 4);
    out.insert(out.end(), events[i].channel.begin(), events[i].channel.end());
    out.insert(out.end(), events[i].data.begin(), events[i].data.end());
  }
  return out;
}

TEST(EventLogFile, FieldChunksComeBackByteForByteAndTakeLessRoomThanPlainZstd) {
  const auto events = field_samples(3000);  // about 4 MB raw, several blocks
  const fs::path file = temporary("fields.lcmlog.zst");
  write_log(file, events);
  EventLogReader reader(file);
  for (std::size_t i = 0; i < events.size(); ++i) {
    const auto event = reader.next();
    ASSERT_TRUE(event) << "event " << i << " missing";
    EXPECT_EQ(event->number, static_cast<int64_t>(i));
    EXPECT_EQ(event->channel, events[i].channel);
    ASSERT_EQ(event->data, events[i].data) << "event " << i;
  }
  EXPECT_FALSE(reader.next());
  EXPECT_GE(reader.blocks().size(), 3u);
  // The same events as one plain LCM log compressed by zstd at the writer's level: the columns
  // must beat it (the reason they exist).
  const auto plain = plain_lcm_log(events);
  std::vector<uint8_t> packed(ZSTD_compressBound(plain.size()));
  const std::size_t zstd_only =
      ZSTD_compress(packed.data(), packed.size(), plain.data(), plain.size(), 3);
  ASSERT_FALSE(ZSTD_isError(zstd_only));
  const auto size = fs::file_size(file);
  std::printf("plain %zu B, zstd alone %zu B (%.1fx), with columns %ju B (%.1fx)\n", plain.size(),
              zstd_only, static_cast<double>(plain.size()) / static_cast<double>(zstd_only),
              static_cast<uintmax_t>(size),
              static_cast<double>(plain.size()) / static_cast<double>(size));
  EXPECT_LT(size, zstd_only);
}

TEST(EventLogFile, ExportedIsAPlainLcmLogAndTheFileAValidZstdStream) {
  auto events = samples(40, 6);
  for (auto& field : field_samples(40)) events.push_back(std::move(field));
  const fs::path file = temporary("plain_check.lcmlog.zst");
  write_log(file, events);
  // Every part is a zstd frame (skippable ones for headers and index): a zstd tool checks it.
  std::ifstream in(file, std::ios::binary);
  const std::vector<char> packed((std::istreambuf_iterator<char>(in)), {});
  ZSTD_DStream* stream = ZSTD_createDStream();
  ZSTD_initDStream(stream);
  std::vector<char> buffer(ZSTD_DStreamOutSize());
  ZSTD_inBuffer input{packed.data(), packed.size(), 0};
  while (input.pos < input.size) {
    ZSTD_outBuffer output{buffer.data(), buffer.size(), 0};
    const std::size_t result = ZSTD_decompressStream(stream, &output, &input);
    ASSERT_FALSE(ZSTD_isError(result)) << ZSTD_getErrorName(result);
  }
  ZSTD_freeDStream(stream);
  const fs::path lcm_file = temporary("plain_check.lcmlog");
  EventLogReader compressed(file);
  EXPECT_EQ(write_lcm_log(compressed, lcm_file), static_cast<int64_t>(events.size()));
  lcm::LogFile log(lcm_file.string(), "r");
  ASSERT_TRUE(log.good());
  std::size_t count = 0;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    ASSERT_LT(count, events.size());
    EXPECT_EQ(event->eventnum, static_cast<int64_t>(count));
    EXPECT_EQ(event->timestamp, events[count].utime);
    EXPECT_EQ(event->channel, events[count].channel);
    ASSERT_EQ(static_cast<std::size_t>(event->datalen), events[count].data.size());
    EXPECT_EQ(std::memcmp(event->data, events[count].data.data(), events[count].data.size()), 0);
    ++count;
  }
  EXPECT_EQ(count, events.size());
  // And our reader takes the plain file as well (runs recorded before compression).
  EventLogReader reader(lcm_file);
  EXPECT_FALSE(reader.compressed());
  std::size_t again = 0;
  while (const auto event = reader.next()) EXPECT_EQ(event->data, events[again++].data);
  EXPECT_EQ(again, events.size());
}

// A log of the first format (plain LCM events in each block, version 1), as earlier builds wrote
// it: one block header frame and one zstd frame, no index.
TEST(EventLogFile, LogsOfTheFirstFormatStillRead) {
  const auto events = samples(20, 6);
  const auto plain = plain_lcm_log(events);
  std::vector<uint8_t> packed(ZSTD_compressBound(plain.size()));
  const std::size_t size =
      ZSTD_compress(packed.data(), packed.size(), plain.data(), plain.size(), 3);
  ASSERT_FALSE(ZSTD_isError(size));
  std::vector<uint8_t> file_bytes;
  const auto le = [&](uint64_t value, int bytes) {
    for (int i = 0; i < bytes; ++i) file_bytes.push_back(static_cast<uint8_t>(value >> (8 * i)));
  };
  le(0x184D2A50u, 4);
  le(48, 4);
  for (char c : {'C', 'S', 'L', 'B'}) file_bytes.push_back(static_cast<uint8_t>(c));
  le(1, 4);  // format version 1
  for (uint64_t field : {static_cast<uint64_t>(size), static_cast<uint64_t>(plain.size()),
                         uint64_t{0}, uint64_t{19}, uint64_t{0}}) {
    le(field, 8);
  }
  file_bytes.insert(file_bytes.end(), packed.begin(), packed.begin() + static_cast<long>(size));
  const fs::path file = temporary("first_format.lcmlog.zst");
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(file_bytes.data()),
             static_cast<long>(file_bytes.size()));
  EventLogReader reader(file);
  EXPECT_TRUE(reader.compressed());
  std::size_t count = 0;
  while (const auto event = reader.next()) {
    ASSERT_LT(count, events.size());
    EXPECT_EQ(event->data, events[count].data);
    ++count;
  }
  EXPECT_EQ(count, events.size());
}

TEST(EventLogFile, SeekingToAWindowStartsAtItsBlock) {
  const auto events = samples(120, 12);
  const fs::path file = temporary("seek.lcmlog.zst");
  write_log(file, events);
  EventLogReader reader(file);
  reader.seek_window(90);
  const auto first = reader.next();
  ASSERT_TRUE(first);
  EXPECT_LE(window_of(*first), 90);
  EXPECT_GT(window_of(*first), 0) << "the seek read from the start";
  int64_t last = window_of(*first);
  bool reached = false;
  while (const auto event = reader.next()) {
    EXPECT_GE(window_of(*event), last);
    last = window_of(*event);
    reached = reached || last == 90;
  }
  EXPECT_TRUE(reached);
}

TEST(EventLogFile, ACutShortLogYieldsItsWholeBlocksThenNamesTheCut) {
  const auto events = samples(120, 12);
  const fs::path file = temporary("cut.lcmlog.zst");
  write_log(file, events);
  const auto size = fs::file_size(file);
  fs::resize_file(file, size / 2);  // inside a block, the index gone
  EventLogReader reader(file);
  EXPECT_GE(reader.blocks().size(), 1u);  // found by walking the block headers
  std::size_t count = 0;
  try {
    while (reader.next()) ++count;
    FAIL() << "a cut log read to its end";
  } catch (const EventLogError& error) {
    EXPECT_NE(std::string(error.what()).find("cut short"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find(file.string()), std::string::npos) << error.what();
  }
  EXPECT_GT(count, 0u);
  EXPECT_LT(count, events.size());
}

TEST(EventLogFile, ACorruptedByteIsNamedWithItsBlock) {
  const auto events = samples(60, 12);
  const fs::path file = temporary("corrupt.lcmlog.zst");
  write_log(file, events);
  {
    std::fstream io(file, std::ios::binary | std::ios::in | std::ios::out);
    io.seekp(200);  // inside the first compressed frame
    char byte = 0;
    io.read(&byte, 1);
    io.seekp(200);
    byte = static_cast<char>(byte ^ 0x5a);
    io.write(&byte, 1);
  }
  EventLogReader reader(file);
  try {
    while (reader.next()) {
    }
    FAIL() << "a corrupted log read to its end";
  } catch (const EventLogError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("damaged at byte"), std::string::npos) << what;
    EXPECT_NE(what.find("windows 0-"), std::string::npos) << what;
  }
}

// A plain log is read record by record and every inconsistency is named with byte and record:
// LCM's own reader would skip the garbage or stop quietly, and a replay would trust the rest.
TEST(EventLogFile, APlainLogNamesAWrongMarkerAGapAndACutWithByteAndRecord) {
  const auto events = samples(10, 3);
  const auto plain = plain_lcm_log(events);
  const auto read_all = [&](const std::vector<uint8_t>& bytes) -> std::string {
    const fs::path file = temporary("strict.lcmlog");
    std::ofstream(file, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<long>(bytes.size()));
    EventLogReader reader(file);
    try {
      while (reader.next()) {
      }
    } catch (const EventLogError& error) {
      return error.what();
    }
    return "";
  };
  EXPECT_EQ(read_all(plain), "");
  const std::size_t second = 28 + events[0].channel.size() + events[0].data.size();
  auto marker = plain;
  marker[second] = 'J';
  EXPECT_NE(read_all(marker).find(fmt::format("damaged at byte {} (record 1): expected the record "
                                              "marker 0xEDA1DA01, found 0x4AA1DA01",
                                              second)),
            std::string::npos)
      << read_all(marker);
  auto gap = plain;
  gap[second + 11] = 7;  // event number 7 where 1 belongs
  EXPECT_NE(read_all(gap).find("(record 1): event number 7 where 1 was expected"),
            std::string::npos)
      << read_all(gap);
  const std::vector<uint8_t> cut(plain.begin(), plain.end() - 5);
  EXPECT_NE(read_all(cut).find("(truncated)"), std::string::npos) << read_all(cut);
}

TEST(EventLogFile, NotAnEventLogIsRefused) {
  const fs::path file = temporary("not_a_log.lcmlog.zst");
  std::ofstream(file) << "name: not a log\n";
  EXPECT_THROW(EventLogReader{file}, EventLogError);
}

TEST(EventLogFile, AFullDiskIsNamed) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const auto events = samples(2, 2);
  try {
    EventLogWriter writer("/dev/full");
    for (const auto& s : events) {
      writer.append(s.channel, s.data.data(), s.data.size(), s.utime, s.window);
    }
    writer.close();
    FAIL() << "writing to /dev/full succeeded";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("No space left on device"), std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("/dev/full"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace cosim::coupler
