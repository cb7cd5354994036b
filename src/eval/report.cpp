// Report writers (include/penumbra/report.h): JSON via nlohmann::json, Markdown and plain-text
// tables by hand (the HTML page is html_report.cpp). Errors are in the units of docs/architecture.md (RMSE8:
// 8-bit steps of V, max error: V), times in milliseconds; the ratio to the baseline is total time
// over the baseline's total time. Scan-line profiles are written rounded to 1e-4 in V (well below
// the 1/255 step of RMSE8), the same values the page plots.
#include "penumbra/report.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/output_file.h"
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

// Text from names and files (a scene's name, a reason) made harmless in Markdown: no raw HTML, no
// line breaks that would end a heading or a list item, no '|' that would end a table cell.
std::string markdownText(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '|')
      out += "\\|";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '\n' || c == '\r' || c == '\0')
      out += ' ';
    else
      out += c;
  }
  return out;
}

bool anyError(const Report& report) {
  return std::any_of(report.rows.begin(), report.rows.end(), [](const ReportRow& r) { return r.error.has_value(); });
}

// The table both text formats print: a header row and one row of cells per technique.
std::vector<std::vector<std::string>> tableCells(const Report& report) {
  const bool withError = anyError(report);
  std::vector<std::vector<std::string>> cells;
  std::vector<std::string> header = {"technique"};
  if (withError) header.insert(header.end(), {"RMSE8", "penumbra RMSE8", "max err", "umbra leaks", "speckle"});
  header.insert(header.end(), {"prepare ms", "visibility ms", "total ms",
                               report.baseline.empty() ? "x baseline" : "x " + report.baseline, "stats", "params"});
  cells.push_back(header);
  for (const ReportRow& row : report.rows) {
    std::vector<std::string> line = {row.shownName()};
    if (withError) {
      if (row.error)
        line.insert(line.end(),
                    {number(row.error->rmse8), number(row.error->penumbraRmse8), number(row.error->maxAbsError, 3),
                     std::to_string(row.error->umbraLeaks), std::to_string(row.error->speckle)});
      else
        line.insert(line.end(), {"-", "-", "-", "-", "-"});
    }
    line.insert(line.end(),
                {number(row.timings.get("prepare")), number(row.timings.get("visibility")), number(row.timings.total()),
                 row.ratioToBaseline ? number(*row.ratioToBaseline) : std::string("-"), joinStats(row.stats),
                 joinParams(row.params)});
    cells.push_back(line);
  }
  // A technique that could not take this scene keeps its row, with the reason where its numbers would be.
  for (const auto& [name, why] : report.skipped) {
    std::vector<std::string> line(header.size(), "-");
    line.front() = name;
    line.back() = "not run here: " + why;
    cells.push_back(line);
  }
  return cells;
}

}  // namespace

std::string describeLight(const Light& light) {
  std::string s(toString(light.shape()));
  switch (light.shape()) {
    case LightShape::Sphere:
      s += fmt::format(" center {} radius {:g}", vec(light.center()), light.radius());
      break;
    case LightShape::Disk:
      s += fmt::format(" center {} normal {} radius {:g}", vec(light.center()), vec(light.normal()), light.radius());
      break;
    case LightShape::Rect:
      s += fmt::format(" center {} u {} v {}", vec(light.center()), vec(light.u()), vec(light.v()));
      break;
    case LightShape::Segment:
      s += fmt::format(" a {} b {}", vec(light.a()), vec(light.b()));
      break;
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
    if (baseMs > 0.0)
      row.ratioToBaseline = row.timings.total() / baseMs;
    else
      row.ratioToBaseline.reset();
  }
}

namespace {

nlohmann::json errorJson(const ErrorStats& e) {
  return {{"rmse8", e.rmse8},
          {"penumbra_rmse8", e.penumbraRmse8},
          {"max_abs_error", e.maxAbsError},
          {"umbra_leaks", e.umbraLeaks},
          {"speckle", e.speckle},
          {"mask_pixels", e.maskPixels},
          {"penumbra_pixels", e.penumbraPixels}};
}

nlohmann::json profileJson(const std::vector<float>& values) {
  nlohmann::json a = nlohmann::json::array();
  for (float v : values) a.push_back(roundedProfileValue(v));
  return a;
}

nlohmann::json temporalJson(const TemporalStats& t) {
  return {{"flicker", t.flicker}, {"pop_rate", t.popRate}, {"reversed_pops", t.reversedPops},
          {"pixels", t.pixels},   {"pops", t.pops},        {"frame_pairs", t.framePairs}};
}

// The sequence table: per technique, the mean still-frame error and the temporal error; the truth's
// noise floor last.
std::vector<std::vector<std::string>> sequenceCells(const Report& report) {
  std::vector<std::vector<std::string>> cells = {
      {"technique", "mean RMSE8", "mean penumbra RMSE8", "flicker", "pop %", "reversed pops %"}};
  const auto temporal = [](const TemporalStats& t) {
    return std::vector<std::string>{fmt::format("{:.2f}", t.flicker), fmt::format("{:.2f}", 100.0 * t.popRate),
                                    fmt::format("{:.1f}", 100.0 * t.reversedPops)};
  };
  for (const ReportRow& row : report.rows) {
    if (!row.sequence || !row.error) continue;
    std::vector<std::string> line = {row.shownName(), fmt::format("{:.2f}", row.error->rmse8),
                                     fmt::format("{:.2f}", row.error->penumbraRmse8)};
    for (std::string& cell : temporal(row.sequence->temporal)) line.push_back(std::move(cell));
    cells.push_back(std::move(line));
  }
  std::vector<std::string> floor = {fmt::format("noise floor (reference, {})", report.sequence->noiseFloorSeeds), "",
                                    ""};
  for (std::string& cell : temporal(report.sequence->noiseFloor)) floor.push_back(std::move(cell));
  cells.push_back(std::move(floor));
  return cells;
}

constexpr const char* kTemporalLegend =
    "flicker = mean |dV - dV_ref| x 255 over the pixels in the penumbra (V or V_ref in (0.01, 0.99)) of two "
    "consecutive frames, dV the change from one frame to the next; pop %: share of those with |dV - dV_ref| > 0.1; "
    "reversed pops %: share of pops undone at the next frame (shimmer). The noise floor is the truth against a "
    "truth of another seed.";

nlohmann::json rowJson(const ReportRow& row) {
  using nlohmann::json;
  json r;
  r["name"] = row.technique;
  r["label"] = row.shownName();
  json params = json::object();
  for (const auto& [k, v] : row.params) params[k] = v;
  r["params"] = params;
  if (row.error) r.update(errorJson(*row.error));
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
  if (row.cached) r["cached"] = true;
  if (!row.profile.empty()) r["profile"] = profileJson(row.profile);
  if (!row.mapSizeSweep.empty()) {
    json sweep = json::array();
    for (const MapSizePoint& p : row.mapSizeSweep) {
      json point = errorJson(p.error);
      point["map_size"] = p.mapSize;
      point["prepare_ms"] = p.timings.get("prepare");
      point["visibility_ms"] = p.timings.get("visibility");
      point["total_ms"] = p.timings.total();
      sweep.push_back(point);
    }
    r["map_size_sweep"] = sweep;
    r["map_size_varies"] = row.mapSizeVaries;
  }
  if (row.sequence) {
    json frames = json::array();
    for (size_t k = 0; k < row.sequence->frames.size(); ++k) {
      json frame = errorJson(row.sequence->frames[k]);
      json images = json::object();
      if (k < row.sequence->images.size())
        for (const auto& [kind, file] : row.sequence->images[k]) images[kind] = file;
      frame["images"] = images;
      frames.push_back(frame);
    }
    r["sequence"] = {{"frames", frames}, {"temporal", temporalJson(row.sequence->temporal)}};
  }
  return r;
}

}  // namespace

double roundedProfileValue(float v) { return std::round(static_cast<double>(v) * 1.0e4) / 1.0e4; }

std::vector<std::string> reportNotes(const Report& report) {
  std::vector<std::string> notes;
  for (const ReportRow& row : report.rows)
    for (const auto& [key, value] : row.stats)
      if (key == "analytic_spheres" && value > 0.0)
        notes.push_back(
            fmt::format("{} traced {} sphere object{} as true spheres (analytic_spheres); the reference and the "
                        "other rows use their tessellated meshes, whose outlines lie just inside the spheres'.",
                        row.shownName(), value, value == 1.0 ? "" : "s"));
  return notes;
}

namespace {

// A table as Markdown; the first column and the last `textColumns` are left-aligned text, the others
// right-aligned numbers.
std::string markdownTable(const std::vector<std::vector<std::string>>& cells, size_t textColumns) {
  std::string md;
  for (size_t r = 0; r < cells.size(); ++r) {
    md += "|";
    for (const std::string& c : cells[r]) md += " " + (c.empty() ? std::string(" ") : markdownText(c)) + " |";
    md += "\n";
    if (r == 0) {
      md += "|";
      for (size_t c = 0; c < cells[0].size(); ++c)
        md += c == 0 || c + textColumns >= cells[0].size() ? "---|" : "---:|";
      md += "\n";
    }
  }
  return md;
}

// The same table aligned for the terminal; the last column is not padded.
std::string textTable(const std::vector<std::vector<std::string>>& cells, size_t textColumns) {
  std::vector<size_t> widths(cells[0].size(), 0);
  for (const auto& line : cells)
    for (size_t c = 0; c < line.size(); ++c) widths[c] = std::max(widths[c], line[c].size());
  std::string text;
  for (const auto& line : cells) {
    std::string out;
    for (size_t c = 0; c < line.size(); ++c) {
      const bool left = c == 0 || c + textColumns >= line.size();
      if (c + 1 == line.size())
        out += line[c];
      else
        out += left ? fmt::format("{:<{}}  ", line[c], widths[c]) : fmt::format("{:>{}}  ", line[c], widths[c]);
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    text += out + "\n";
  }
  return text;
}

}  // namespace

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
  if (!report.command.empty()) j["command"] = report.command;
  if (!report.files.empty()) {
    json files = json::object();
    for (const auto& [k, v] : report.files) files[k] = v;
    j["files"] = files;
  }
  if (report.truth) j["truth"] = rowJson(*report.truth);
  if (report.errorMapRange > 0.0) j["error_map_range"] = report.errorMapRange;
  if (!report.mapSizes.empty()) j["map_sizes"] = report.mapSizes;
  if (report.profile) {
    json mask = json::array();
    for (uint8_t m : report.profile->mask) mask.push_back(m ? 1 : 0);
    j["profile"] = {{"row", report.profile->row},
                    {"choice", report.profile->choice},
                    {"reference", profileJson(report.profile->reference)},
                    {"mask", mask}};
  }
  if (const std::vector<std::string> notes = reportNotes(report); !notes.empty()) j["notes"] = notes;
  if (!report.skipped.empty()) {
    json skipped = json::array();
    for (const auto& [name, why] : report.skipped) skipped.push_back({{"name", name}, {"reason", why}});
    j["skipped"] = skipped;
  }
  if (report.sequence)
    j["sequence"] = {{"frames", report.sequence->frames},
                     {"motion", report.sequence->motion},
                     {"noise_floor", temporalJson(report.sequence->noiseFloor)},
                     {"noise_floor_seeds", report.sequence->noiseFloorSeeds}};
  json rows = json::array();
  for (const ReportRow& row : report.rows) rows.push_back(rowJson(row));
  j["techniques"] = rows;
  return j.dump(2) + "\n";
}

std::string reportToMarkdown(const Report& report) {
  std::string md = fmt::format("# penumbra {}: {}\n\n", report.kind, markdownText(report.scene));
  md += fmt::format("- scene: {} ({})\n", markdownText(report.scene), markdownText(report.sceneSource));
  md += fmt::format("- light {}: {}\n", report.lightIndex, report.light);
  md += fmt::format("- image: {} x {}\n", report.width, report.height);
  if (!report.baseline.empty())
    md += fmt::format("- time ratios relative to `{}`, measured in the same run\n", report.baseline);
  for (const auto& [k, v] : report.settings) md += fmt::format("- {}: {}\n", k, v);
  if (report.truth)
    md += fmt::format("- truth: `reference` {}{}\n", joinParams(report.truth->params),
                      report.truth->cached ? " (read from the reference cache)" : "");
  if (report.profile)
    md += fmt::format("- scan-line profile: row {} ({})\n", report.profile->row, report.profile->choice);
  md += fmt::format("- penumbra {}\n", report.version);
  if (!report.command.empty()) md += fmt::format("- reproduce: `{}`\n", report.command);
  md += "\n";
  if (anyError(report))
    md +=
        "RMSE8 = sqrt(mean((V - V_ref)^2)) x 255 over pixels facing the light; penumbra RMSE8 over those where "
        "V or V_ref is in (0.01, 0.99); max err in V; umbra leaks: pixels with V_ref < 0.05 and V > 0.5; "
        "speckle: pixels whose V is more than 0.25 from the median of its 3x3 block where V_ref's is within 0.05 "
        "of its own. The reference row's error is 0 by definition: its own noise is its standard error in the "
        "stats column.\n\n";
  md += markdownTable(tableCells(report), 2);
  if (report.sequence) {
    md += fmt::format("\n## Over the sequence\n\n{} frames, {}. {}\n\n", report.sequence->frames,
                      markdownText(report.sequence->motion), kTemporalLegend);
    md += markdownTable(sequenceCells(report), 0);
  }
  if (!report.mapSizes.empty() && anyError(report)) {
    md +=
        "\n## RMSE8 against shadow-map size\n\nOne column per map size (texels per side); a technique without a map "
        "size ran once and repeats its value.\n\n| technique |";
    for (int size : report.mapSizes) md += fmt::format(" {} |", size);
    md += "\n|---|";
    for (size_t i = 0; i < report.mapSizes.size(); ++i) md += "---:|";
    md += "\n";
    for (const ReportRow& row : report.rows) {
      if (row.mapSizeSweep.size() != report.mapSizes.size()) continue;
      md += fmt::format("| {}{} |", row.shownName(), row.mapSizeVaries ? "" : " (no map)");
      for (const MapSizePoint& p : row.mapSizeSweep) md += fmt::format(" {} |", number(p.error.rmse8));
      md += "\n";
    }
  }
  if (const std::vector<std::string> notes = reportNotes(report); !notes.empty()) {
    md += "\n## Notes\n\n";
    for (const std::string& note : notes) md += "- " + note + "\n";
  }
  if (!report.skipped.empty()) {
    md += "\n## Not run\n\n";
    for (const auto& [name, why] : report.skipped) md += fmt::format("- `{}`: {}\n", name, markdownText(why));
  }
  bool anyImages = false;
  for (const ReportRow& row : report.rows) anyImages = anyImages || !row.images.empty();
  if (anyImages) {
    md += "\n## Images\n\n";
    for (const ReportRow& row : report.rows) {
      if (row.images.empty()) continue;
      md += fmt::format("**{}**:", row.shownName());
      for (const auto& [kind, file] : row.images) md += fmt::format(" [{}]({})", kind, file);
      md += "\n\n";
    }
  }
  return md;
}

std::string reportToText(const Report& report) {
  std::string text = textTable(tableCells(report), 2);
  if (report.sequence) {
    text += fmt::format("\nover {} frames ({}):\n", report.sequence->frames, report.sequence->motion);
    text += textTable(sequenceCells(report), 0);
  }
  for (const std::string& note : reportNotes(report)) text += "note: " + note + "\n";
  return text;
}

void writeTextFile(const std::string& path, const std::string& text) {
  replaceFile(path, [&](const std::string& temp) {
    std::ofstream file(temp, std::ios::binary | std::ios::trunc);
    if (!file)
      fail("cannot write '{}': the file cannot be opened (check that the directory exists and is writable)", path);
    file << text;
    file.close();
    if (!file) fail("cannot write '{}': the write failed (disk full?)", path);
  });
}

}  // namespace penumbra
