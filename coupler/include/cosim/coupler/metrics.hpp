// A participant's final report: metrics, each with its unit and, where the scene names one,
// its reference and relative error. `cosim` prints these and writes them to summary.json.
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

namespace cosim::coupler {

class MetricsReport {
 public:
  void value(const std::string& name, double value, const std::string& unit) {
    json_["metrics"][name] = {{"value", value}, {"unit", unit}};
  }
  void compare(const std::string& name, double value, double reference, const std::string& unit,
               const std::string& reference_source) {
    const double error = reference != 0.0 ? std::abs(value - reference) / std::abs(reference)
                                          : std::abs(value - reference);
    json_["metrics"][name] = {{"value", value},
                              {"unit", unit},
                              {"reference", reference},
                              {"relative_error", error},
                              {"reference_source", reference_source}};
  }
  // An error measure that is itself the comparison (e.g. a relative RMS error against measured
  // points), with the source it is measured against.
  void error(const std::string& name, double relative_error, const std::string& reference_source) {
    json_["metrics"][name] = {{"value", relative_error},
                              {"unit", "relative"},
                              {"relative_error", relative_error},
                              {"reference_source", reference_source}};
  }
  // Anything else worth keeping (stability flags, counts, series names).
  nlohmann::json& info() { return json_["info"]; }
  std::string dump() const { return json_.dump(); }
  // Takes over a report recorded earlier (a JSON object text), e.g. a replayed participant's.
  void merge(const std::string& report_json) {
    json_.merge_patch(nlohmann::json::parse(report_json));
  }

 private:
  nlohmann::json json_ = nlohmann::json::object();
};

}  // namespace cosim::coupler
