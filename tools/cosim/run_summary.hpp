// What a run leaves beside its outputs: summary.json (the outcome, every participant's report,
// traffic, implicit iterations, coupling overhead) and, for implicit schemes,
// implicit_convergence.csv.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "runner.hpp"

namespace cosim::tool {

// "SIGINT", or "signal N" where the C library has no abbreviation.
std::string signal_name(int signal);

// summary.json of a finished (or failed, or interrupted) run.
nlohmann::json summary_of(const scenario::Scene& scene, const RunRequest& request,
                          const RunOutcome& outcome, int64_t run_id, const std::string& url,
                          const std::optional<ResolvedRestart>& restart);

// Each implicit coupling iteration's convergence measure, a row per iteration (preCICE writes
// the same as its convergence log): the window, its start, the iteration and every exchanged
// field's residual over its tolerance (<= 1 converged), so a window at the limit shows whether
// its residuals stalled, oscillated or grew. Empty for explicit schemes.
std::string convergence_csv(const coupler::RunResult& result);

}  // namespace cosim::tool
