// The schedule of the particle loops whose work per particle is uneven (only fluid particles
// work, or only particles with a row of their own). Particles are in cell order, so in a long
// channel the bed's wall and dummy particles fill whole stretches of the index range: with one
// contiguous half per thread, one thread may get most of the water. Chunks of kParticleChunk
// are handed out on demand (schedule(dynamic, kParticleChunk)): handed out in turn, the main
// thread, which also runs the step's serial parts, finished its chunks 5-15 % later than the
// other (perf by thread, honami_field), which then waited. Each particle's result is its own, so
// the schedule changes no bit of it.
#pragma once

namespace cosim::mps {

inline constexpr int kParticleChunk = 256;

}  // namespace cosim::mps
