#include "cosim/debris_dem/checkpoint.hpp"

namespace cosim::dem {

// Every member that changes after the scene is built. Elements, pair slots and states are
// fixed-layout structs stored as they are in memory; the stored element size refuses a file of
// a build with another layout.
struct DemWorldCheckpoint {
  template <class World, class Visit>
  static void vectors(World& w, Visit&& v) {
    v("dem.elements", w.elements_);
    v("dem.damping_clipped", w.damping_clipped_);
    v("dem.damping_unclipped", w.damping_unclipped_);
    v("dem.moving", w.moving_);
    v("dem.force", w.force_);
    v("dem.torque", w.torque_);
    v("dem.mean_fluid_force", w.mean_fluid_force_);
    v("dem.mean_interaction_force", w.mean_interaction_force_);
    v("dem.submerged_fraction", w.submerged_fraction_);
    v("dem.voidage", w.voidage_);
    v("dem.added_mass_normal", w.added_mass_normal_);
    v("dem.added_mass_axial", w.added_mass_axial_);
    v("dem.fluid_acceleration", w.fluid_acceleration_);
    v("dem.pair_slots", w.pair_slots_);
    v("dem.pair_states", w.pair_states_);
    v("dem.hot_position", w.hot_position_);
    v("dem.hot_velocity", w.hot_velocity_);
    v("dem.gravity_force", w.gravity_force_);
    v("dem.pair_results", w.pair_results_);
    v("dem.triangle_pairs", w.triangle_pairs_);
    v("dem.triangle_group_start", w.triangle_group_start_);
  }
  template <class World, class Visit>
  static void values(World& w, Visit&& v) {
    v("dem.hot_valid", w.hot_valid_);
    v("dem.sweep_largest", w.sweep_largest_);
    v("dem.sweep_second", w.sweep_second_);
    v("dem.sweep_top_valid", w.sweep_top_valid_);
    v("dem.gravity_force_for", w.gravity_force_for_);
    v("dem.time", w.time_);
    v("dem.time_since_list", w.time_since_list_);
    v("dem.window_max_overlap", w.window_max_overlap_);
    v("dem.step_count", w.step_count_);
    v("dem.list_rebuilds", w.list_rebuilds_);
    v("dem.list_valid", w.list_valid_);
    v("dem.gate_active", w.gate_active_);
    v("dem.gate_count", w.gate_count_);
  }

  static void save(const DemWorld& w, checkpoint::Writer& out) {
    out.value("dem.schema", kDemCheckpointSchema);
    out.value("dem.material_count", static_cast<std::uint64_t>(w.materials_.size()));
    vectors(w, [&](const char* name, const auto& v) { out.vector(name, v); });
    values(w, [&](const char* name, const auto& v) { out.value(name, v); });
  }

  static void load(DemWorld& w, const checkpoint::Reader& in) {
    if (const auto schema = in.value<std::uint32_t>("dem.schema"); schema != kDemCheckpointSchema) {
      in.fail("dem.schema", "is " + std::to_string(schema) + " where this build reads " +
                                std::to_string(kDemCheckpointSchema));
    }
    const std::size_t elements = w.elements_.size();
    if (const auto n = in.vector<DemWorld::Element>("dem.elements").size(); n != elements) {
      in.fail("dem.elements", "holds " + std::to_string(n) + " elements where this scene has " +
                                  std::to_string(elements));
    }
    if (const auto n = in.value<std::uint64_t>("dem.material_count"); n != w.materials_.size()) {
      in.fail("dem.material_count", "is " + std::to_string(n) + " where this scene has " +
                                        std::to_string(w.materials_.size()));
    }
    vectors(w, [&](const char* name, auto& v) {
      v = in.vector<typename std::decay_t<decltype(v)>::value_type>(name);
    });
    values(w, [&](const char* name, auto& v) { v = in.value<std::decay_t<decltype(v)>>(name); });
  }
};

void save_checkpoint(const DemWorld& world, checkpoint::Writer& out) {
  DemWorldCheckpoint::save(world, out);
}

void load_checkpoint(DemWorld& world, const checkpoint::Reader& in) {
  DemWorldCheckpoint::load(world, in);
}

}  // namespace cosim::dem
