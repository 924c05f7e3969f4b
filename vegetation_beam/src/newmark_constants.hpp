// Constants shared by the sub-step-synchronous (plant_field_newmark.cpp) and the plant-by-plant
// (plant_field_apart.cpp) Newmark windows.
#pragma once

namespace cosim::vegetation {

inline constexpr double kBeta = 0.25;  // Newmark average acceleration (seed eq. 22-23)
inline constexpr double kGamma = 0.5;
// From this many plants the plants out of contact are solved side by side (OpenMP); under it
// the fork and join cost more than the work.
inline constexpr int kPlantsSideBySide = 16;
// With contact on, a window solved plant by plant keeps the start positions of its sub-steps for
// the contact candidates' updates (sub-steps x nodes): at most this many (24 MB); a window that
// would need more is solved sub-step by sub-step.
inline constexpr long long kApartMostKeptPositions = 1 << 20;

}  // namespace cosim::vegetation
