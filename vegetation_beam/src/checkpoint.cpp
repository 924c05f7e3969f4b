#include "cosim/vegetation_beam/checkpoint.hpp"

namespace cosim::vegetation {

// The members that carry over from one window to the next. The contact candidate list and the
// contact bookkeeping are kept as they were (not rebuilt at load): the list's order decides the
// order of the contact force sums, and a rebuild at other positions would change the last bits.
struct PlantFieldCheckpoint {
  template <class Field, class Visit>
  static void visit(Field& f, Visit&& v) {
    v("plants.positions", f.positions_, true);
    v("plants.velocities", f.velocities_, true);
    v("plants.accelerations", f.accelerations_, true);
    v("plants.external_forces", f.external_forces_, true);
    v("plants.body_forces", f.body_forces_, true);
    v("plants.water_fraction", f.water_fraction_, true);
    v("plants.window_mean_drag", f.window_mean_drag_, true);
    v("plants.contact_forces", f.contact_forces_, true);
    v("plants.candidate_positions", f.candidate_positions_, false);  // empty before a search
    v("plants.contact_candidates", f.contact_candidates_, false);
    v("plants.contact_active", f.contact_active_, false);
    v("plants.contact_touched_nodes", f.contact_touched_nodes_, false);
    v("plants.plant_in_contact", f.plant_in_contact_, false);
  }

  static void save(const PlantField& f, checkpoint::Writer& out) {
    out.value("plants.schema", kPlantCheckpointSchema);
    out.value("plants.node_count", static_cast<std::uint64_t>(f.positions_.size()));
    visit(f, [&](const char* name, const auto& values, bool) { out.vector(name, values); });
    std::vector<int> pairs;  // per plant: count, then the candidate indices
    for (const auto& plant : f.plant_contact_pairs_) {
      pairs.push_back(static_cast<int>(plant.size()));
      pairs.insert(pairs.end(), plant.begin(), plant.end());
    }
    out.vector("plants.plant_contact_pairs", pairs);
    const char flags[3] = {f.candidates_valid_, f.accelerations_valid_, f.robust_first_};
    out.bytes("plants.flags", flags, 1, 3);
    out.value("plants.time", f.time_);
  }

  static void load(PlantField& f, const checkpoint::Reader& in) {
    if (const auto schema = in.value<std::uint32_t>("plants.schema");
        schema != kPlantCheckpointSchema) {
      in.fail("plants.schema", "is " + std::to_string(schema) + " where this build reads " +
                                   std::to_string(kPlantCheckpointSchema));
    }
    const std::size_t n = f.positions_.size();
    if (const auto saved = in.value<std::uint64_t>("plants.node_count"); saved != n) {
      in.fail("plants.node_count", "is " + std::to_string(saved) + " where this scene has " +
                                       std::to_string(n) + " nodes");
    }
    visit(f, [&](const char* name, auto& values, bool per_node) {
      if (per_node) {
        in.vector_into(name, values);
      } else {
        values = in.vector<typename std::decay_t<decltype(values)>::value_type>(name);
      }
    });
    const auto pairs = in.vector<int>("plants.plant_contact_pairs");
    // No record entries: saved before the first contact search (an implicit window's start).
    f.plant_contact_pairs_.assign(pairs.empty() ? 0 : f.plants_.size(), {});
    std::size_t at = 0;
    for (auto& plant : f.plant_contact_pairs_) {
      if (at >= pairs.size() || pairs[at] < 0 ||
          static_cast<std::size_t>(pairs[at]) > pairs.size() - at - 1) {
        in.fail("plants.plant_contact_pairs", "does not match this scene's plants");
      }
      plant.assign(pairs.begin() + at + 1, pairs.begin() + at + 1 + pairs[at]);
      at += 1 + static_cast<std::size_t>(pairs[at]);
    }
    const auto flags = in.vector<char>("plants.flags");
    if (flags.size() != 3) in.fail("plants.flags", "must hold 3 flags");
    f.candidates_valid_ = flags[0] != 0;
    f.accelerations_valid_ = flags[1] != 0;
    f.robust_first_ = flags[2] != 0;
    f.time_ = in.value<double>("plants.time");
    f.clearance_valid_ = false;  // checked again at the next window (it decides no bits)
  }
};

void save_checkpoint(const PlantField& field, checkpoint::Writer& out) {
  PlantFieldCheckpoint::save(field, out);
}

void load_checkpoint(PlantField& field, const checkpoint::Reader& in) {
  PlantFieldCheckpoint::load(field, in);
}

}  // namespace cosim::vegetation
