// Write errors of the output writers (disk full through /dev/full, which fails every write with
// ENOSPC) are reported with the file and the cause, and leave no temporary file behind.
#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "cosim/output/files.hpp"
#include "cosim/output/point_series.hpp"

namespace cosim::output {
namespace {

std::filesystem::path folder(const std::string& name) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("cosim-write-errors-" + name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(path);
  std::filesystem::create_directories(path);
  return path;
}

bool has_dev_full() {
  return std::filesystem::exists("/dev/full");
}

std::string read(const std::filesystem::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), {}};
}

TEST(WriteErrors, AFullDiskNamesTheFileAndTheCauseAndKeepsThePreviousContent) {
  if (!has_dev_full()) GTEST_SKIP() << "no /dev/full";
  const auto dir = folder("atomic");
  const auto file = dir / "summary.json";
  std::ofstream(file) << "previous";
  // The temporary file the writer creates is the full device.
  std::filesystem::create_symlink("/dev/full", dir / "summary.json.tmp");
  try {
    write_file_atomically(file, std::string(100000, 'x'));
    FAIL() << "no error on a full disk";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()),
              "cannot write '" + file.string() + "': No space left on device");
  }
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(dir / "summary.json.tmp")))
      << "the temporary file is removed";
  EXPECT_EQ(read(file), "previous");
}

TEST(WriteErrors, AnUnwritableFolderIsNamed) {
  try {
    write_file_atomically("/proc/no-such-folder/summary.json", "x");
    FAIL() << "no error";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()),
              "cannot write '/proc/no-such-folder/summary.json': No such file or directory");
  }
}

TEST(WriteErrors, TheXdmfIndexOnAFullDiskIsReportedAndItsTemporaryFileRemoved) {
  if (!has_dev_full()) GTEST_SKIP() << "no /dev/full";
  const auto dir = folder("xdmf");
  std::filesystem::create_symlink("/dev/full", dir / "plants.xmf.tmp");
  try {
    PointSeriesWriter writer(dir / "plants", "test");
    FAIL() << "no error on a full disk";
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find((dir / "plants.xmf").string()), std::string::npos) << message;
    EXPECT_NE(message.find("No space left on device"), std::string::npos) << message;
  }
  EXPECT_FALSE(std::filesystem::exists(std::filesystem::symlink_status(dir / "plants.xmf.tmp")));
}

TEST(WriteErrors, HdfFramesOnAFullDiskAreReportedWithTheFileAndTheCause) {
  if (!has_dev_full()) GTEST_SKIP() << "no /dev/full";
  const auto dir = folder("hdf5");
  std::filesystem::create_symlink("/dev/full", dir / "plants.h5");
  try {
    PointSeriesWriter writer(dir / "plants", "test");
    PointFrame frame;
    frame.positions.assign(1000, Eigen::Vector3d(1, 2, 3));
    frame.scalars["pressure"].assign(1000, 1.0);
    for (int i = 0; i < 5; ++i) {
      frame.time = i;
      writer.write_frame(frame);
    }
    FAIL() << "no error on a full disk";
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find((dir / "plants.h5").string()), std::string::npos) << message;
    EXPECT_NE(message.find("No space left on device"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace cosim::output
