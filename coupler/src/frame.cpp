#include "cosim/coupler/frame.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "cosim/scenario/scene.hpp"

namespace cosim::coupler {

std::string FrameDeclaration::to_json() const {
  nlohmann::json json;
  json["frame"] = frame;
  json["dimension"] = dimension;
  json["span"] = span;
  json["gravity"] = {gravity.x(), gravity.y(), gravity.z()};
  json["limits_window"] = limits_window;
  return json.dump();
}

FrameDeclaration FrameDeclaration::from_json(const std::string& text, const std::string& who) {
  if (text.empty()) {
    throw std::runtime_error(fmt::format(
        "'{}' declared no world frame at the handshake (a participant of another build?)", who));
  }
  try {
    const auto json = nlohmann::json::parse(text);
    FrameDeclaration declaration;
    declaration.frame = json.at("frame").get<std::string>();
    declaration.dimension = json.at("dimension").get<int>();
    declaration.span = json.at("span").get<double>();
    const auto gravity = json.at("gravity").get<std::vector<double>>();
    if (gravity.size() != 3) throw std::runtime_error("gravity needs 3 values");
    declaration.gravity = Eigen::Vector3d(gravity[0], gravity[1], gravity[2]);
    declaration.limits_window = json.value("limits_window", true);
    return declaration;
  } catch (const std::exception& error) {
    throw std::runtime_error(
        fmt::format("'{}' sent a malformed frame declaration '{}': {}", who, text, error.what()));
  }
}

namespace {

std::string describe(const Eigen::Vector3d& v) {
  return fmt::format("({:.6g}, {:.6g}, {:.6g})", v.x(), v.y(), v.z());
}

}  // namespace

std::string check_declarations(
    const std::vector<std::pair<std::string, FrameDeclaration>>& declarations,
    const scenario::WorldSettings& world) {
  const double g_tolerance = 1e-9 * std::max(1.0, world.gravity.norm());
  const std::pair<std::string, FrameDeclaration>* first_2d = nullptr;
  for (const auto& entry : declarations) {
    const auto& [name, declaration] = entry;
    const auto& [first_name, first] = declarations.front();
    if (declaration.frame != first.frame) {
      return fmt::format("'{}' works in the frame \"{}\" but '{}' in \"{}\"", name,
                         declaration.frame, first_name, first.frame);
    }
    if (declaration.frame != kWorldFrame) {
      return fmt::format("'{}' works in the frame \"{}\", not this run's \"{}\"", name,
                         declaration.frame, kWorldFrame);
    }
    if ((declaration.gravity - first.gravity).norm() > g_tolerance) {
      return fmt::format("'{}' declares gravity {} m/s^2 but '{}' declares {}", name,
                         describe(declaration.gravity), first_name, describe(first.gravity));
    }
    if (declaration.dimension != 2 && declaration.dimension != 3) {
      return fmt::format("'{}' declares dimension {} (2 or 3)", name, declaration.dimension);
    }
    if (declaration.dimension == 3) continue;
    if (!(declaration.span > 0.0) || !std::isfinite(declaration.span)) {
      return fmt::format("'{}' is 2D but declares no span width (got {} m)", name,
                         declaration.span);
    }
    if (std::abs(declaration.gravity.y()) > g_tolerance) {
      return fmt::format("'{}' is 2D in the x-z plane but gravity {} has a y component", name,
                         describe(declaration.gravity));
    }
    if (first_2d && std::abs(first_2d->second.span - declaration.span) >
                        1e-12 * std::max(1.0, declaration.span)) {
      return fmt::format("'{}' stands for a span of {} m but '{}' for {} m", name, declaration.span,
                         first_2d->first, first_2d->second.span);
    }
    if (!first_2d) first_2d = &entry;
  }
  // They agree with each other; all of them may still differ from the scene (a replay of a run
  // in another world, or a process of another build).
  for (const auto& [name, declaration] : declarations) {
    if ((declaration.gravity - world.gravity).norm() > g_tolerance) {
      return fmt::format("'{}' declares gravity {} m/s^2 but the scene's world has {}", name,
                         describe(declaration.gravity), describe(world.gravity));
    }
  }
  return {};
}

SolverFrame::SolverFrame(int dimension, double span) : dimension_(dimension), span_(span) {
  if (dimension != 2 && dimension != 3) throw std::invalid_argument("dimension must be 2 or 3");
  if (dimension == 2 && !(span > 0.0)) throw std::invalid_argument("a 2D frame needs a span > 0");
  if (dimension == 3) span_ = 1.0;
}

Eigen::Vector3d SolverFrame::to_solver(const Eigen::Vector3d& world) const {
  return dimension_ == 3 ? world : Eigen::Vector3d(world.x(), world.z(), 0.0);
}

Eigen::Vector3d SolverFrame::to_world(const Eigen::Vector3d& solver) const {
  return dimension_ == 3 ? solver : Eigen::Vector3d(solver.x(), 0.0, solver.y());
}

Eigen::Vector3d SolverFrame::force_to_solver(const Eigen::Vector3d& world_force) const {
  return to_solver(world_force) / span_;
}

Eigen::Vector3d SolverFrame::force_to_world(const Eigen::Vector3d& solver_force) const {
  return to_world(solver_force) * span_;
}

Eigen::Vector3d SolverFrame::out_of_plane(const Eigen::Vector3d& world) const {
  return dimension_ == 3 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0.0, world.y(), 0.0);
}

}  // namespace cosim::coupler
