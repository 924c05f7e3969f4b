// Reading a scenario file: duplicate keys at any depth, files that are not regular files, and
// files above the size limit are refused with the file (and line and key) named.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <future>

#include "cosim/scenario/document.hpp"
#include "cosim/scenario/section.hpp"

namespace cosim::scenario {
namespace {

std::filesystem::path folder() {
  static const auto dir = [] {
    auto path = std::filesystem::temp_directory_path() /
                ("cosim-document-test-" + std::to_string(getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    return path;
  }();
  return dir;
}

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto file = folder() / name;
  std::ofstream(file) << text;
  return file;
}

std::string error_of(const std::filesystem::path& file, std::uintmax_t limit = kMaxScenarioBytes) {
  try {
    load_document(file, limit);
  } catch (const ScenarioError& error) {
    return error.what();
  }
  return "";
}

TEST(Document, ADuplicateTopLevelKeyIsNamedWithBothLines) {
  const auto file = write("top.yaml", "name: a\nduration: 1\nname: b\n");
  EXPECT_EQ(error_of(file), file.string() + ":3: key 'name': appears twice (first at line 1)");
}

TEST(Document, ADuplicateNestedKeyIsNamedWithItsDottedKey) {
  const auto file =
      write("nested.yaml", "coupling:\n  window: 1.0e-3\n  timeout: 2\n  window: 2.0e-3\n");
  EXPECT_EQ(error_of(file),
            file.string() + ":4: key 'coupling.window': appears twice (first at line 2)");
}

TEST(Document, ADuplicateKeyInAListItemIsNamedWithItsIndex) {
  const auto file = write("list.yaml",
                          "participants:\n"
                          "  vegetation_beam:\n"
                          "    plants:\n"
                          "      - length: 0.04\n"
                          "      - length: 0.05\n"
                          "        width: 0.002\n"
                          "        length: 0.06\n");
  EXPECT_EQ(error_of(file), file.string() +
                                ":7: key 'participants.vegetation_beam.plants[1].length': appears "
                                "twice (first at line 5)");
}

TEST(Document, ADuplicateKeyInFlowStyleIsFound) {
  const auto file = write("flow.yaml", "world: {slope_degrees: 5, slope_degrees: 6}\n");
  EXPECT_NE(error_of(file).find("key 'world.slope_degrees': appears twice"), std::string::npos)
      << error_of(file);
}

TEST(Document, TheSameKeyInDifferentMappingsIsFine) {
  const auto file = write("fine.yaml", "a:\n  x: 1\nb:\n  x: 2\nc:\n  - x: 1\n  - x: 2\n");
  EXPECT_EQ(error_of(file), "");
  EXPECT_EQ(load_yaml_file(file)["b"]["x"].as<int>(), 2);
}

TEST(Document, ADirectoryIsRefusedByName) {
  const auto dir = folder() / "scenario.yaml";
  std::filesystem::create_directories(dir);
  EXPECT_EQ(error_of(dir),
            dir.string() + ": is a directory, not a scenario file (a regular file is needed)");
}

TEST(Document, AFifoIsRefusedAtOnceWithoutBlocking) {
  const auto fifo = folder() / "fifo.yaml";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // Opening a FIFO for reading blocks until a writer comes: run it aside with a time limit.
  auto loaded = std::async(std::launch::async, [&] { return error_of(fifo); });
  if (loaded.wait_for(std::chrono::seconds(5)) != std::future_status::ready) {
    std::ofstream release(fifo);  // lets the blocked reader go, so the test ends
    FAIL() << "load_document blocked on a FIFO";
  }
  EXPECT_EQ(loaded.get(), fifo.string() +
                              ": is a FIFO (named pipe), not a scenario file (a regular file is "
                              "needed)");
}

TEST(Document, ACharacterDeviceIsRefused) {
  EXPECT_EQ(error_of("/dev/zero"),
            "/dev/zero: is a character device, not a scenario file (a regular file is needed)");
}

TEST(Document, AFileAboveTheLimitIsRefusedWithItsSizeAndTheLimit) {
  const auto file = write("big.yaml", "name: " + std::string(2000, 'x') + "\n");
  EXPECT_EQ(
      error_of(file, 1024),
      file.string() + ": is 2007 bytes (2007 bytes); scenario files are limited to 1024 bytes");
  // The default limit, on a sparse file of 100 MB: refused at once, without reading it.
  const auto sparse = folder() / "sparse.yaml";
  std::ofstream(sparse).close();
  std::filesystem::resize_file(sparse, 100'000'000);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(error_of(sparse), sparse.string() +
                                  ": is 95.4 MiB (100000000 bytes); scenario files are limited "
                                  "to 16.0 MiB");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
}

TEST(Document, AMissingFileAndASyntaxErrorAreNamed) {
  EXPECT_EQ(error_of(folder() / "absent.yaml"),
            (folder() / "absent.yaml").string() + ": file not found");
  const auto file = write("syntax.yaml", "a: 1\nb: [1, 2\n");
  EXPECT_NE(error_of(file).find(file.string() + ":"), std::string::npos) << error_of(file);
  EXPECT_NE(error_of(file).find("YAML syntax error"), std::string::npos) << error_of(file);
}

}  // namespace
}  // namespace cosim::scenario
