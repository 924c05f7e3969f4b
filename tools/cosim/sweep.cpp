#include "sweep.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "plot.hpp"

namespace cosim::tool {

namespace {

std::filesystem::path scenario_file_of(const std::filesystem::path& bundle) {
  return std::filesystem::is_directory(bundle) ? bundle / "scenario.yaml" : bundle;
}

void apply_all(YAML::Node& document, const std::vector<std::string>& overrides) {
  for (const auto& item : overrides) {
    const auto equals = item.find('=');
    if (equals == std::string::npos) {
      throw scenario::ScenarioError("--set expects KEY=VALUE, got '" + item + "'");
    }
    scenario::apply_override(document, item.substr(0, equals), item.substr(equals + 1));
  }
}

}  // namespace

scenario::Scene load_with_overrides(const std::filesystem::path& bundle,
                                    const std::vector<std::string>& overrides) {
  const auto file = scenario_file_of(bundle);
  YAML::Node document = scenario::load_yaml_file(file);
  apply_all(document, overrides);
  return scenario::load_scene(document, file, participant_parsers());
}

nlohmann::json sweep_figure(const std::string& scene, const std::string& vary,
                            const std::vector<SweepRow>& rows, const std::filesystem::path& file) {
  const std::string key = vary.substr(vary.rfind('.') + 1);
  // metric -> (wall, value or error, label), in the order of the runs.
  std::map<std::string, nlohmann::json> errors, values;
  std::map<std::string, std::string> units;
  for (const auto& row : rows) {
    for (const auto& [name, metric] : row.metrics) {
      const std::string label = key + "=" + row.value;
      if (metric.contains("relative_error") && metric["relative_error"].is_number()) {
        auto& curve = errors[name];
        curve["x"].push_back(row.wall);
        curve["y"].push_back(100 * metric["relative_error"].get<double>());
        curve["annotations"].push_back(label);
      }
      if (metric.contains("value") && metric["value"].is_number()) {
        auto& curve = values[name];
        curve["x"].push_back(row.wall);
        curve["y"].push_back(metric["value"].get<double>());
        curve["annotations"].push_back(label);
        units[name] = metric.value("unit", "");
      }
    }
  }
  nlohmann::json figure{{"file", file.string()}};
  if (!errors.empty()) {
    nlohmann::json lines = nlohmann::json::array();
    for (auto& [name, curve] : errors) {
      curve["label"] = name;
      curve["style"] = "points";
      lines.push_back(curve);
    }
    figure["title"] = fmt::format("{}: error against run time, varying {}", scene, vary);
    figure["xlabel"] = "wall time [s]";
    figure["ylabel"] = "relative error [%]";
    figure["xscale"] = "log";
    figure["yscale"] = "log";
    figure["lines"] = lines;
    return figure;
  }
  // No metric has a reference here: show how each value moves with the cost.
  nlohmann::json panels = nlohmann::json::array();
  for (auto& [name, curve] : values) {
    curve["label"] = name;
    curve["style"] = "points";
    const std::string& unit = units[name];
    panels.push_back({{"title", name},
                      {"xlabel", "wall time [s]"},
                      {"ylabel", unit.empty() ? name : fmt::format("{} [{}]", name, unit)},
                      {"xscale", "log"},
                      {"lines", nlohmann::json::array({curve})}});
  }
  if (panels.empty()) {
    panels.push_back({{"title", "no metric reported"}, {"xlabel", "wall time [s]"}});
  }
  figure["title"] =
      fmt::format("{}: metrics against run time, varying {} (no reference)", scene, vary);
  figure["panels"] = panels;
  return figure;
}

int sweep(const SweepRequest& request) {
  // Before any run: a sweep may take hours, and its figure needs matplotlib.
  if (request.plot) plotting_python();
  const auto file = scenario_file_of(request.bundle);
  const YAML::Node original = scenario::load_yaml_file(file);
  // Check every variant before running any.
  std::vector<scenario::Scene> scenes;
  for (const auto& value : request.values) {
    YAML::Node document = YAML::Clone(original);
    apply_all(document, request.overrides);
    scenario::apply_override(document, request.vary, value);
    scenes.push_back(scenario::load_scene(document, file, participant_parsers()));
    check_run_request(scenes.back(), request.run);  // a bad --fault stops the sweep at once
  }
  using Row = SweepRow;
  std::vector<Row> rows;
  int exit_code = 0;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    fmt::print("sweep {}/{}: {} = {}\n", i + 1, scenes.size(), request.vary, request.values[i]);
    std::fflush(stdout);  // before the run's progress lines on stderr
    RunRequest run = request.run;
    run.run_label = fmt::format("sweep{}", i + 1);
    const auto outcome = run_scene(scenes[i], run);
    if (outcome.interrupted_by != 0) {
      // Ctrl-C stops the sweep, not only the run that was going.
      fmt::print(stderr, "{}\n", interruption_line(outcome));
      return outcome.exit_code;
    }
    Row row{request.values[i], outcome.result.ok, outcome.result.wall_seconds, {}, outcome.run_dir};
    std::ifstream in(outcome.run_dir / "summary.json");
    const auto summary = nlohmann::json::parse(in);
    for (const auto& participant : summary["participants"]) {
      const auto& report = participant["report"];
      if (!report.contains("metrics")) continue;
      for (const auto& [name, metric] : report["metrics"].items()) {
        row.metrics.emplace_back(participant["name"].get<std::string>() + "." + name, metric);
      }
    }
    if (!outcome.result.ok) {
      exit_code = 1;
      fmt::print("  failed: {}\n", outcome.result.failure);
    }
    rows.push_back(std::move(row));
  }

  // Table and CSV: one line per run and metric.
  const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::filesystem::create_directories(request.run.runs_dir);
  const auto csv_path = std::filesystem::absolute(
      request.run.runs_dir /
      fmt::format("{}-sweep-{:%Y%m%d-%H%M%S}.csv", scenes.front().name, fmt::localtime(now)));
  std::ofstream csv(csv_path);
  csv << request.vary << ",ok,wall_seconds,metric,value,unit,reference,relative_error,run_dir\n";
  fmt::print("\n{:<14} {:>9}  {:<44} {:>12} {:>12} {:>9}\n",
             request.vary.substr(request.vary.rfind('.') + 1), "wall [s]", "metric", "value",
             "reference", "error %");
  for (const auto& row : rows) {
    if (row.metrics.empty()) {
      fmt::print("{:<14} {:>9.2f}  {}\n", row.value, row.wall, row.ok ? "(no metrics)" : "FAILED");
      csv << fmt::format("{},{},{},,,,,,{}\n", row.value, row.ok, row.wall, row.run_dir.string());
    }
    for (const auto& [name, metric] : row.metrics) {
      const double value = metric["value"].get<double>();
      const bool has_reference = metric.contains("reference");
      const bool has_error = metric.contains("relative_error");
      const std::string reference =
          has_reference ? fmt::format("{:.6g}", metric["reference"].get<double>()) : "";
      const std::string error =
          has_error ? fmt::format("{:.3f}", 100 * metric["relative_error"].get<double>()) : "";
      fmt::print("{:<14} {:>9.2f}  {:<44} {:>12.6g} {:>12} {:>9}\n", row.value, row.wall, name,
                 value, reference, error);
      csv << fmt::format("{},{},{},{},{},{},{},{},{}\n", row.value, row.ok, row.wall, name, value,
                         metric.value("unit", ""), reference,
                         has_error ? fmt::format("{}", metric["relative_error"].get<double>()) : "",
                         row.run_dir.string());
    }
  }
  csv.close();
  fmt::print("\ntable written to {}\n", csv_path.string());
  if (request.plot) {
    auto png_path = csv_path;
    png_path.replace_extension(".png");
    try {
      draw_figures(
          {{"figures", {sweep_figure(scenes.front().name, request.vary, rows, png_path)}}});
      fmt::print("figure written to {}\n", png_path.string());
    } catch (const PlotError& error) {
      fmt::print(stderr, "error: no figure ({}); the table is complete\n", error.what());
      return exit_code != 0 ? exit_code : 2;
    }
  }
  return exit_code;
}

}  // namespace cosim::tool
