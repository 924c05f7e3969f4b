// Checkpoint files keep every bit, and a file that was cut, changed, or written by another
// format version is refused with its name, never read wrongly.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "cosim/checkpoint/archive.hpp"

namespace cosim::checkpoint {
namespace {

std::filesystem::path scratch(const std::string& name) {
  const auto folder = std::filesystem::temp_directory_path() / "cosim_checkpoint_test";
  std::filesystem::create_directories(folder);
  return folder / name;
}

std::filesystem::path sample_file(const std::string& name) {
  Writer out("sample");
  out.value("answer", 42);
  out.vector("values", std::vector<double>{1.0, -0.0, std::numeric_limits<double>::denorm_min(),
                                           std::nan("7")});
  out.text("label", "plants");
  out.vector("empty", std::vector<int>{});
  const auto path = scratch(name);
  EXPECT_GT(out.save(path), 0u);
  return path;
}

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

TEST(CheckpointArchive, RoundTripKeepsEveryBit) {
  const auto path = sample_file("round_trip.ckpt");
  const Reader in(path, "sample");
  EXPECT_EQ(in.value<int>("answer"), 42);
  const auto values = in.vector<double>("values");
  ASSERT_EQ(values.size(), 4u);
  EXPECT_TRUE(std::signbit(values[1]));
  EXPECT_EQ(values[2], std::numeric_limits<double>::denorm_min());
  EXPECT_TRUE(std::isnan(values[3]));
  EXPECT_EQ(in.text("label"), "plants");
  EXPECT_TRUE(in.vector<int>("empty").empty());
  EXPECT_EQ(verify(path).kind, "sample");
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".part"));
}

TEST(CheckpointArchive, WrongRecordsAreNamed) {
  const Reader in(sample_file("records.ckpt"), "sample");
  EXPECT_NE(error_of([&] { in.value<double>("missing"); }).find("record 'missing' is missing"),
            std::string::npos);
  EXPECT_NE(error_of([&] { in.vector<float>("values"); }).find("8-byte values"), std::string::npos);
  std::vector<double> three(3);
  EXPECT_NE(error_of([&] { in.vector_into("values", three); }).find("holds 4 values"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              Reader(sample_file("kind.ckpt"), "debris_dem");
            }).find("a checkpoint of 'sample', not of 'debris_dem'"),
            std::string::npos);
}

TEST(CheckpointArchive, DamageIsRefusedWithTheFileNamed) {
  const auto path = sample_file("damaged.ckpt");
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  auto write = [&](const std::string& name, const std::string& content) {
    const auto file = scratch(name);
    std::ofstream(file, std::ios::binary | std::ios::trunc) << content;
    return file;
  };
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x01;
  const auto changed = write("flipped.ckpt", flipped);
  EXPECT_NE(error_of([&] { verify(changed); }).find(changed.string() + ": damaged checkpoint"),
            std::string::npos);
  EXPECT_NE(error_of([&] { Reader{changed}; }).find("checksum mismatch"), std::string::npos);
  const auto cut = write("cut.ckpt", bytes.substr(0, bytes.size() - 9));
  EXPECT_NE(error_of([&] { verify(cut); }).find(cut.string()), std::string::npos);
  std::string other_version = bytes;
  other_version[8] = 9;
  const auto version = write("version.ckpt", other_version);
  EXPECT_NE(error_of([&] { verify(version); }).find("format version 9"), std::string::npos);
  const auto not_one = write("text.ckpt", "name: a scenario, not a checkpoint\n");
  EXPECT_NE(error_of([&] { verify(not_one); }).find("not a checkpoint file"), std::string::npos);
  EXPECT_NE(error_of([&] { verify(scratch("absent.ckpt")); }).find("cannot open"),
            std::string::npos);
}

TEST(CheckpointArchive, KnownCrc32) {
  // The check value of CRC-32/IEEE.
  EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);
}

}  // namespace
}  // namespace cosim::checkpoint
