#include "sweep.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <algorithm>
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

namespace {

// One run of a sweep or a spread: its label in the tables, its overrides and its progress line.
struct Variant {
  std::string label;
  std::vector<std::string> overrides;
  std::string title;
};

struct VariantRuns {
  std::vector<SweepRow> rows;
  std::string scene;
  int exit_code = 0;  // 1 when a run failed; an interrupted run's code, which stops them all
  bool interrupted = false;
};

// Every variant is checked before any runs: a sweep may take hours.
VariantRuns run_variants(const std::filesystem::path& bundle,
                         const std::vector<std::string>& overrides,
                         const std::vector<Variant>& variants, const RunRequest& request,
                         const std::string& command) {
  const auto file = scenario_file_of(bundle);
  const YAML::Node original = scenario::load_yaml_file(file);
  std::vector<scenario::Scene> scenes;
  for (const auto& variant : variants) {
    YAML::Node document = YAML::Clone(original);
    apply_all(document, overrides);
    apply_all(document, variant.overrides);
    scenes.push_back(scenario::load_scene(document, file, participant_parsers()));
    check_run_request(scenes.back(), request);  // a bad --fault stops them at once
  }
  VariantRuns result;
  result.scene = scenes.front().name;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    fmt::print("{} {}/{}: {}\n", command, i + 1, scenes.size(), variants[i].title);
    std::fflush(stdout);  // before the run's progress lines on stderr
    RunRequest run = request;
    run.run_label = fmt::format("{}{}", command, i + 1);
    const auto outcome = run_scene(scenes[i], run);
    if (outcome.interrupted_by != 0) {
      // Ctrl-C stops them all, not only the run that was going.
      fmt::print(stderr, "{}\n", interruption_line(outcome));
      result.exit_code = outcome.exit_code;
      result.interrupted = true;
      return result;
    }
    SweepRow row{
        variants[i].label, outcome.result.ok, outcome.result.wall_seconds, {}, outcome.run_dir};
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
      result.exit_code = 1;
      fmt::print("  failed: {}\n", outcome.result.failure);
    }
    result.rows.push_back(std::move(row));
  }
  return result;
}

// Table and CSV: one line per run and metric. Returns the CSV's path.
std::filesystem::path write_table(const VariantRuns& runs, const std::string& command,
                                  const std::string& column, const std::string& column_title,
                                  const std::filesystem::path& runs_dir) {
  const auto now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::filesystem::create_directories(runs_dir);
  const auto csv_path =
      std::filesystem::absolute(runs_dir / fmt::format("{}-{}-{:%Y%m%d-%H%M%S}.csv", runs.scene,
                                                       command, fmt::localtime(now)));
  std::ofstream csv(csv_path);
  csv << column << ",ok,wall_seconds,metric,value,unit,reference,relative_error,run_dir\n";
  std::size_t width = std::max<std::size_t>(14, column_title.size());
  for (const auto& row : runs.rows) width = std::max(width, row.value.size());
  fmt::print("\n{:<{}} {:>9}  {:<44} {:>12} {:>12} {:>9}\n", column_title, width, "wall [s]",
             "metric", "value", "reference", "error %");
  for (const auto& row : runs.rows) {
    // A label with a comma is quoted in the CSV.
    const std::string label =
        row.value.find(',') == std::string::npos ? row.value : "\"" + row.value + "\"";
    if (row.metrics.empty()) {
      fmt::print("{:<{}} {:>9.2f}  {}\n", row.value, width, row.wall,
                 row.ok ? "(no metrics)" : "FAILED");
      csv << fmt::format("{},{},{},,,,,,{}\n", label, row.ok, row.wall, row.run_dir.string());
    }
    for (const auto& [name, metric] : row.metrics) {
      const double value = metric["value"].get<double>();
      const bool has_reference = metric.contains("reference");
      const bool has_error = metric.contains("relative_error");
      const std::string reference =
          has_reference ? fmt::format("{:.6g}", metric["reference"].get<double>()) : "";
      const std::string error =
          has_error ? fmt::format("{:.3f}", 100 * metric["relative_error"].get<double>()) : "";
      fmt::print("{:<{}} {:>9.2f}  {:<44} {:>12.6g} {:>12} {:>9}\n", row.value, width, row.wall,
                 name, value, reference, error);
      csv << fmt::format("{},{},{},{},{},{},{},{},{}\n", label, row.ok, row.wall, name, value,
                         metric.value("unit", ""), reference,
                         has_error ? fmt::format("{}", metric["relative_error"].get<double>()) : "",
                         row.run_dir.string());
    }
  }
  fmt::print("\ntable written to {}\n", csv_path.string());
  return csv_path;
}

}  // namespace

int sweep(const SweepRequest& request) {
  // Before any run: a sweep may take hours, and its figure needs matplotlib.
  if (request.plot) plotting_python();
  std::vector<Variant> variants;
  for (const auto& value : request.values) {
    variants.push_back({value, {request.vary + "=" + value}, request.vary + " = " + value});
  }
  // The values are labels; --vary's key applies them (an '=' in a value is part of it).
  const auto runs = run_variants(request.bundle, request.overrides, variants, request.run, "sweep");
  if (runs.interrupted) return runs.exit_code;
  const auto csv_path =
      write_table(runs, "sweep", request.vary, request.vary.substr(request.vary.rfind('.') + 1),
                  request.run.runs_dir);
  if (request.plot) {
    auto png_path = csv_path;
    png_path.replace_extension(".png");
    try {
      draw_figures({{"figures", {sweep_figure(runs.scene, request.vary, runs.rows, png_path)}}});
      fmt::print("figure written to {}\n", png_path.string());
    } catch (const PlotError& error) {
      fmt::print(stderr, "error: no figure ({}); the table is complete\n", error.what());
      return runs.exit_code != 0 ? runs.exit_code : 2;
    }
  }
  return runs.exit_code;
}

std::vector<MetricSpread> metric_spreads(const std::vector<SweepRow>& rows) {
  std::vector<MetricSpread> spreads;
  if (rows.empty()) return spreads;
  const auto number = [](const nlohmann::json& metric, const char* key, double& out) {
    if (!metric.contains(key) || !metric[key].is_number()) return false;
    out = metric[key].get<double>();
    return true;
  };
  for (const auto& [name, metric] : rows.front().metrics) {
    MetricSpread spread;
    spread.name = name;
    spread.unit = metric.value("unit", "");
    if (!number(metric, "value", spread.base_value)) continue;
    spread.has_error = number(metric, "relative_error", spread.base_error);
    spread.min_value = spread.max_value = spread.base_value;
    spread.min_error = spread.max_error = spread.base_error;
    for (const auto& row : rows) {
      for (const auto& [other, entry] : row.metrics) {
        double value = 0, error = 0;
        if (other != name || !number(entry, "value", value)) continue;
        ++spread.runs;
        spread.min_value = std::min(spread.min_value, value);
        spread.max_value = std::max(spread.max_value, value);
        if (spread.has_error && number(entry, "relative_error", error)) {
          spread.min_error = std::min(spread.min_error, error);
          spread.max_error = std::max(spread.max_error, error);
        }
        break;
      }
    }
    spreads.push_back(spread);
  }
  return spreads;
}

int spread(const SpreadRequest& request) {
  std::vector<Variant> variants{{"bundle", {}, "bundle"}};
  for (const auto& perturbation : request.perturbations) {
    const auto equals = perturbation.find('=');
    if (equals == std::string::npos) {
      throw scenario::ScenarioError("--perturb expects KEY=VALUE, got '" + perturbation + "'");
    }
    // Labelled by the key's last part and the value: pcg_tolerance=1e-9.
    const auto key = perturbation.substr(0, equals);
    const std::string label = key.substr(key.rfind('.') + 1) + perturbation.substr(equals);
    variants.push_back({label, {perturbation}, label});
  }
  const auto runs =
      run_variants(request.bundle, request.overrides, variants, request.run, "spread");
  if (runs.interrupted) return runs.exit_code;
  write_table(runs, "spread", "perturbation", "perturbation", request.run.runs_dir);
  fmt::print(
      "\nspread over {} runs (the bundle and {} perturbation{}): the range is how far a "
      "metric moves by itself, in points of its error, or in its unit without a reference\n",
      runs.rows.size(), runs.rows.size() - 1, runs.rows.size() == 2 ? "" : "s");
  fmt::print("{:<44} {:>4} {:>12} {:>12} {:>12} {:>9} {:>9} {:>9} {:>9}\n", "metric", "runs",
             "value", "min", "max", "error %", "min %", "max %", "range");
  for (const auto& m : metric_spreads(runs.rows)) {
    if (m.has_error) {
      fmt::print("{:<44} {:>4} {:>12.6g} {:>12.6g} {:>12.6g} {:>9.3f} {:>9.3f} {:>9.3f} {:>9.3f}\n",
                 m.name, m.runs, m.base_value, m.min_value, m.max_value, 100 * m.base_error,
                 100 * m.min_error, 100 * m.max_error, 100 * (m.max_error - m.min_error));
    } else {
      fmt::print("{:<44} {:>4} {:>12.6g} {:>12.6g} {:>12.6g} {:>9} {:>9} {:>9} {:>9.3g}\n", m.name,
                 m.runs, m.base_value, m.min_value, m.max_value, "", "", "",
                 m.max_value - m.min_value);
    }
  }
  return runs.exit_code;
}

}  // namespace cosim::tool
