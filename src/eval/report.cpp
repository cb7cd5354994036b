// Report writers (include/penumbra/report.h): JSON via nlohmann::json, Markdown and plain-text
// tables by hand. Errors are in the units of DESIGN.md (RMSE8: 8-bit steps of V, max error: V),
// times in milliseconds; the ratio to the baseline is total time over the baseline's total time.
#include "penumbra/report.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "penumbra/error.h"

namespace penumbra {

namespace {

std::string vec(const Vec3& v) { return fmt::format("({:g}, {:g}, {:g})", v.x, v.y, v.z); }

std::string number(double v, int precision = 2) {
  if (!std::isfinite(v)) return "-";
  return fmt::format("{:.{}f}", v, precision);
}

std::string joinStats(const std::vector<std::pair<std::string, double>>& stats) {
  std::string s;
  for (const auto& [k, v] : stats) s += fmt::format("{}{}={:.4g}", s.empty() ? "" : " ", k, v);
  return s;
}

std::string joinParams(const KeyValues& params) {
  std::string s;
  for (const auto& [k, v] : params) s += fmt::format("{}{}={}", s.empty() ? "" : " ", k, v);
  return s;
}

bool anyError(const Report& report) {
  return std::any_of(report.rows.begin(), report.rows.end(), [](const ReportRow& r) { return r.error.has_value(); });
}

// The table both text formats print: a header row and one row of cells per technique.
std::vector<std::vector<std::string>> tableCells(const Report& report) {
  const bool withError = anyError(report);
  std::vector<std::vector<std::string>> cells;
  std::vector<std::string> header = {"technique"};
  if (withError) header.insert(header.end(), {"RMSE8", "penumbra RMSE8", "max err"});
  header.insert(header.end(), {"prepare ms", "visibility ms", "total ms",
                               report.baseline.empty() ? "x baseline" : "x " + report.baseline, "stats", "params"});
  cells.push_back(header);
  for (const ReportRow& row : report.rows) {
    std::vector<std::string> line = {row.technique};
    if (withError) {
      if (row.error)
        line.insert(line.end(), {number(row.error->rmse8), number(row.error->penumbraRmse8),
                                 number(row.error->maxAbsError, 3)});
      else
        line.insert(line.end(), {"-", "-", "-"});
    }
    line.insert(line.end(), {number(row.timings.get("prepare")), number(row.timings.get("visibility")),
                             number(row.timings.total()),
                             row.ratioToBaseline ? number(*row.ratioToBaseline) : std::string("-"),
                             joinStats(row.stats), joinParams(row.params)});
    cells.push_back(line);
  }
  return cells;
}

}  // namespace

std::string describeLight(const Light& light) {
  std::string s(toString(light.shape()));
  switch (light.shape()) {
    case LightShape::Sphere: s += fmt::format(" center {} radius {:g}", vec(light.center()), light.radius()); break;
    case LightShape::Disk:
      s += fmt::format(" center {} normal {} radius {:g}", vec(light.center()), vec(light.normal()), light.radius());
      break;
    case LightShape::Rect: s += fmt::format(" center {} u {} v {}", vec(light.center()), vec(light.u()), vec(light.v())); break;
    case LightShape::Segment: s += fmt::format(" a {} b {}", vec(light.a()), vec(light.b())); break;
    case LightShape::Polygon:
      s += fmt::format(" {} vertices, center {}", light.vertices().size(), vec(light.center()));
      break;
    case LightShape::Directional:
      s += fmt::format(" direction {} angular diameter {:g} deg, {}", vec(light.direction()),
                       degrees(light.angularDiameter()), toString(light.profile()));
      break;
  }
  return s + fmt::format(", intensity {:g}", light.intensity());
}

KeyValues describeParams(const Params& params) {
  KeyValues out;
  for (const auto& [name, value] : params.values()) out.emplace_back(name, value ? formatParamValue(*value) : "auto");
  return out;
}

void fillBaselineRatios(Report& report) {
  const ReportRow* base = nullptr;
  for (const ReportRow& row : report.rows)
    if (row.technique == report.baseline) base = &row;
  const double baseMs = base ? base->timings.total() : 0.0;
  for (ReportRow& row : report.rows) {
    if (baseMs > 0.0) row.ratioToBaseline = row.timings.total() / baseMs;
    else row.ratioToBaseline.reset();
  }
}

std::string reportToJson(const Report& report) {
  using nlohmann::json;
  json j;
  j["kind"] = report.kind;
  j["penumbra_version"] = report.version;
  j["scene"] = {{"name", report.scene}, {"source", report.sceneSource}};
  j["light"] = {{"index", report.lightIndex}, {"description", report.light}};
  j["image"] = {{"width", report.width}, {"height", report.height}};
  j["baseline"] = report.baseline.empty() ? json(nullptr) : json(report.baseline);
  json settings = json::object();
  for (const auto& [k, v] : report.settings) settings[k] = v;
  j["settings"] = settings;
  json rows = json::array();
  for (const ReportRow& row : report.rows) {
    json r;
    r["name"] = row.technique;
    json params = json::object();
    for (const auto& [k, v] : row.params) params[k] = v;
    r["params"] = params;
    if (row.error) {
      r["rmse8"] = row.error->rmse8;
      r["penumbra_rmse8"] = row.error->penumbraRmse8;
      r["max_abs_error"] = row.error->maxAbsError;
      r["mask_pixels"] = row.error->maskPixels;
      r["penumbra_pixels"] = row.error->penumbraPixels;
    }
    r["prepare_ms"] = row.timings.get("prepare");
    r["visibility_ms"] = row.timings.get("visibility");
    r["total_ms"] = row.timings.total();
    json passes = json::array();
    for (const auto& [name, ms] : row.timings.passes) passes.push_back({{"pass", name}, {"ms", ms}});
    r["passes"] = passes;
    r["ratio_to_baseline"] = row.ratioToBaseline ? json(*row.ratioToBaseline) : json(nullptr);
    json stats = json::object();
    // Non-finite values have no JSON form; null says "not measured" rather than inventing a number.
    for (const auto& [k, v] : row.stats) stats[k] = std::isfinite(v) ? json(v) : json(nullptr);
    r["stats"] = stats;
    json images = json::object();
    for (const auto& [k, v] : row.images) images[k] = v;
    r["images"] = images;
    rows.push_back(r);
  }
  j["techniques"] = rows;
  return j.dump(2) + "\n";
}

std::string reportToMarkdown(const Report& report) {
  std::string md = fmt::format("# penumbra {}: {}\n\n", report.kind, report.scene);
  md += fmt::format("- scene: `{}` ({})\n", report.scene, report.sceneSource);
  md += fmt::format("- light {}: {}\n", report.lightIndex, report.light);
  md += fmt::format("- image: {} x {}\n", report.width, report.height);
  if (!report.baseline.empty()) md += fmt::format("- time ratios relative to `{}`, measured in the same run\n", report.baseline);
  for (const auto& [k, v] : report.settings) md += fmt::format("- {}: {}\n", k, v);
  md += fmt::format("- penumbra {}\n\n", report.version);
  if (anyError(report))
    md += "RMSE8 = sqrt(mean((V - V_ref)^2)) x 255 over pixels facing the light; penumbra RMSE8 over those where "
          "V or V_ref is in (0.01, 0.99); max err in V. The reference row's error is 0 by definition: its own "
          "noise is its standard error in the stats column.\n\n";
  const auto cells = tableCells(report);
  for (size_t r = 0; r < cells.size(); ++r) {
    md += "|";
    for (const std::string& c : cells[r]) md += " " + (c.empty() ? std::string(" ") : c) + " |";
    md += "\n";
    if (r == 0) {
      md += "|";
      for (size_t c = 0; c < cells[0].size(); ++c) md += c == 0 || c + 2 >= cells[0].size() ? "---|" : "---:|";
      md += "\n";
    }
  }
  bool anyImages = false;
  for (const ReportRow& row : report.rows) anyImages = anyImages || !row.images.empty();
  if (anyImages) {
    md += "\n## Images\n\n";
    for (const ReportRow& row : report.rows) {
      if (row.images.empty()) continue;
      md += fmt::format("**{}**:", row.technique);
      for (const auto& [kind, file] : row.images) md += fmt::format(" [{}]({})", kind, file);
      md += "\n\n";
    }
  }
  return md;
}

std::string reportToText(const Report& report) {
  const auto cells = tableCells(report);
  std::vector<size_t> widths(cells[0].size(), 0);
  for (const auto& line : cells)
    for (size_t c = 0; c < line.size(); ++c) widths[c] = std::max(widths[c], line[c].size());
  std::string text;
  for (const auto& line : cells) {
    std::string out;
    for (size_t c = 0; c < line.size(); ++c) {
      // Numbers right-aligned, names and free text left-aligned; the last column is not padded.
      const bool left = c == 0 || c + 2 >= line.size();
      if (c + 1 == line.size()) out += line[c];
      else out += left ? fmt::format("{:<{}}  ", line[c], widths[c]) : fmt::format("{:>{}}  ", line[c], widths[c]);
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    text += out + "\n";
  }
  return text;
}

void writeTextFile(const std::string& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) fail("cannot write '{}': the file cannot be opened (check that the directory exists and is writable)", path);
  file << text;
  file.close();
  if (!file) fail("cannot write '{}': the write failed (disk full?)", path);
}

}  // namespace penumbra
