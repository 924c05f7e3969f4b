// Checked HDF5 access (hdf5_access.hpp): error messages and the file-level helpers.
#include "hdf5_access.hpp"

#include <stdexcept>

namespace cosim::output::detail {
namespace {

herr_t take_innermost(unsigned n, const H5E_error2_t* err, void* data) {
  if (n == 0 && err != nullptr && err->desc != nullptr) {
    *static_cast<std::string*>(data) = err->desc;
  }
  return 0;
}

// HDF5's file driver reports a failed system call as "file write failed: time = ..., filename
// = ..., errno = 28, error message = 'No space left on device', buf = 0x..., ...": keep what
// names the cause, drop the clock, the pointers and the byte counts.
std::string shorten_driver_message(const std::string& message) {
  const std::string marker = "error message = '";
  const auto start = message.find(marker);
  if (start == std::string::npos) return message;
  const auto end = message.find('\'', start + marker.size());
  if (end == std::string::npos) return message;
  const std::string cause = message.substr(start + marker.size(), end - start - marker.size());
  return message.substr(0, message.find(':')) + ": " + cause;
}

std::string hdf5_message() {
  std::string message;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, take_innermost, &message);
  H5Eclear2(H5E_DEFAULT);
  return message.empty() ? std::string() : " (" + shorten_driver_message(message) + ")";
}

}  // namespace

void silence_hdf5() {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& object,
                       const std::string& what) {
  // "/" stands for the file itself, which needs no separate object name.
  const std::string target =
      object == "/" ? "'" + file.string() + "'" : "'" + object + "' in '" + file.string() + "'";
  throw std::runtime_error("cosim_output: " + what + " " + target + " failed" + hdf5_message());
}

std::string frame_group(int index) {
                         char buffer[32];
                         std::snprintf(buffer, sizeof buffer, "/frames/%06d", index);
                         return buffer;
                       }

                       std::vector<double> flatten(const std::vector<Eigen::Vector3d>& points) {
                         std::vector<double> flat;
                         flat.reserve(points.size() * 3);
                         for (const auto& p : points)
                           flat.insert(flat.end(), {p.x(), p.y(), p.z()});
                         return flat;
                       }

                       std::vector<Eigen::Vector3d> unflatten(const std::vector<double>& flat) {
                         std::vector<Eigen::Vector3d> points(flat.size() / 3);
                         for (std::size_t i = 0; i < points.size(); ++i) {
                           points[i] =
                               Eigen::Vector3d(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]);
                         }
                         return points;
                       }

                       Handle access_list(const Checker& c) {
                         Handle fapl = c.id(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "/",
                                            "creating access list for");
#if H5_VERSION_GE(1, 10, 7)
                         c.ok(H5Pset_file_locking(fapl.get(), false, true), "/",
                              "disabling file locking for");
#endif
                         return fapl;
                       }

                       Handle open_for_reading(const std::filesystem::path& h5_path) {
                         silence_hdf5();
                         std::error_code ec;
                         if (!std::filesystem::is_regular_file(h5_path, ec)) {
                           throw std::runtime_error("cosim_output: no such file '" +
                                                    h5_path.string() + "'");
                         }
                         const Checker c{h5_path};
                         Handle fapl = access_list(c);
                         return c.id(H5Fopen(h5_path.string().c_str(), H5F_ACC_RDONLY, fapl.get()),
                                     H5Fclose, "/", "opening HDF5 file");
                       }

                       int frames_in(const Checker& c, hid_t file) {
                         Handle frames = c.open_group(file, "/frames", "/frames");
                         H5G_info_t info;
                         c.ok(H5Gget_info(frames.get(), &info), "/frames", "listing group");
                         return static_cast<int>(info.nlinks);
                       }

                       }  // namespace cosim::output::detail
