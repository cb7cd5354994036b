// The HTML page of a comparison report (include/penumbra/report.h, reportToHtml): one file with
// its CSS, a little JavaScript (table sorting, showing/hiding a technique in the plots) and inline
// SVG plots, referring to the images beside it by relative file name, so that it opens from disk
// with no network. Everything is drawn here, in C++, from the Report: the page reads the same
// numbers as compare.json and shows them even with scripts off. Table cells carry the unrounded
// number in data-value (what sorting uses and what tests check against the JSON).
//
// Plots: error against time (log time axis, since the techniques span 0.01 ms to seconds; the
// non-dominated points, the quality-per-millisecond front, joined by a dashed line), RMSE8 against
// shadow-map size (log2 axis) when a sweep ran, and V along the profile's scan line.
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "eval/report_figures.h"
#include "penumbra/report.h"

namespace penumbra {

namespace {

std::string esc(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Shortest text that reads back to the same double: what nlohmann::json writes too.
std::string exact(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string(); }
std::string fixed(double v, int precision) { return std::isfinite(v) ? fmt::format("{:.{}f}", v, precision) : "-"; }
// SVG coordinates: two decimals are a hundredth of a pixel.
std::string coord(double v) { return fmt::format("{:.2f}", v); }

std::string hex(const Srgb8& c) { return fmt::format("#{:02x}{:02x}{:02x}", c[0], c[1], c[2]); }

// Okabe & Ito's colour-blind-safe palette, then Tableau's, for the techniques; the truth is black.
std::string techniqueColor(size_t index) {
  static const char* palette[] = {"#0072b2", "#e69f00", "#009e73", "#cc79a7", "#d55e00", "#56b4e9",
                                  "#f0e442", "#7f7f7f", "#8c564b", "#9467bd", "#bcbd22", "#17becf",
                                  "#e377c2", "#2ca02c", "#ff7f0e", "#1f77b4"};
  return palette[index % std::size(palette)];
}
constexpr const char* kTruthColor = "#000000";

// ---- plots -------------------------------------------------------------------------------------

struct Scale {
  double lo = 0.0, hi = 1.0;
  bool log = false;
  double a = 0.0, b = 1.0;  //!< pixel range
  double operator()(double v) const {
    const double t = log ? (std::log(v) - std::log(lo)) / (std::log(hi) - std::log(lo)) : (v - lo) / (hi - lo);
    return a + t * (b - a);
  }
};

// Round numbers (1, 2, 5 x 10^k) in [lo, hi], about `count` of them; with `extend`, one more past
// hi when hi is not itself a tick, so that an axis ending at the last tick holds every value.
std::vector<double> niceTicks(double lo, double hi, int count, bool extend = false) {
  const double span = hi - lo;
  if (!(span > 0.0)) return {lo};
  const double raw = span / count;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  double step = p;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) {
      step = m * p;
      break;
    }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  if (extend && (ticks.empty() || ticks.back() < hi - 1e-9 * step))
    ticks.push_back(ticks.empty() ? hi : ticks.back() + step);
  return ticks;
}

std::vector<double> logTicks(double lo, double hi) {
  std::vector<double> ticks;
  const int k0 = static_cast<int>(std::floor(std::log10(lo))), k1 = static_cast<int>(std::ceil(std::log10(hi)));
  const bool fewDecades = k1 - k0 <= 2;
  for (int k = k0; k <= k1; ++k)
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !fewDecades) continue;
      const double t = m * std::pow(10.0, k);
      if (t >= lo * (1 - 1e-9) && t <= hi * (1 + 1e-9)) ticks.push_back(t);
    }
  return ticks;
}

std::string tickLabel(double v) {
  if (v == 0.0) return "0";
  if (std::abs(v) >= 1000 || std::abs(v) < 0.01) return fmt::format("{:g}", v);
  return fmt::format("{:g}", std::round(v * 1000.0) / 1000.0);
}

struct Plot {
  static constexpr double kWidth = 720, kHeight = 400, kLeft = 64, kRight = 20, kTop = 16, kBottom = 52;
  Scale x, y;
  std::string body;

  Plot(Scale xs, Scale ys) : x(xs), y(ys) {
    x.a = kLeft;
    x.b = kWidth - kRight;
    y.a = kHeight - kBottom;
    y.b = kTop;
  }

  std::string frame(const std::string& id, const std::string& title, const std::string& xLabel,
                    const std::string& yLabel, const std::vector<double>& xTicks, const std::vector<double>& yTicks,
                    const std::vector<std::string>& xTickLabels = {}) const {
    std::string s = fmt::format(
        "<svg id=\"{}\" class=\"plot\" viewBox=\"0 0 {} {}\" role=\"img\" aria-label=\"{}\" "
        "xmlns=\"http://www.w3.org/2000/svg\">\n",
        id, kWidth, kHeight, esc(title));
    s += fmt::format("<rect class=\"plot-bg\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/>\n", kLeft, kTop,
                     kWidth - kLeft - kRight, kHeight - kTop - kBottom);
    for (size_t i = 0; i < xTicks.size(); ++i) {
      const double px = x(xTicks[i]);
      s += fmt::format(
          "<line class=\"grid\" x1=\"{0}\" x2=\"{0}\" y1=\"{1}\" y2=\"{2}\"/>"
          "<text class=\"tick\" x=\"{0}\" y=\"{3}\" text-anchor=\"middle\">{4}</text>\n",
          coord(px), coord(kTop), coord(kHeight - kBottom), coord(kHeight - kBottom + 16),
          esc(i < xTickLabels.size() ? xTickLabels[i] : tickLabel(xTicks[i])));
    }
    for (double t : yTicks) {
      const double py = y(t);
      s += fmt::format(
          "<line class=\"grid\" x1=\"{0}\" x2=\"{1}\" y1=\"{2}\" y2=\"{2}\"/>"
          "<text class=\"tick\" x=\"{3}\" y=\"{4}\" text-anchor=\"end\">{5}</text>\n",
          coord(kLeft), coord(kWidth - kRight), coord(py), coord(kLeft - 6), coord(py + 4), esc(tickLabel(t)));
    }
    s += fmt::format("<text class=\"axis-label\" x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n",
                     coord(0.5 * (kLeft + kWidth - kRight)), coord(kHeight - 12), esc(xLabel));
    s += fmt::format(
        "<text class=\"axis-label\" transform=\"translate(16 {}) rotate(-90)\" text-anchor=\"middle\">{}"
        "</text>\n",
        coord(0.5 * (kTop + kHeight - kBottom)), esc(yLabel));
    return s + body + "</svg>\n";
  }
};

double maxOr(const std::vector<double>& v, double fallback) {
  double m = fallback;
  for (double x : v) m = std::max(m, x);
  return m;
}

// Every row with an error: a point at (total ms, RMSE8); the front joins the points no other point
// beats in both time and error.
std::string errorTimePlot(const Report& report) {
  struct Point {
    size_t row;
    double ms, rmse8;
  };
  std::vector<Point> points;
  for (size_t i = 0; i < report.rows.size(); ++i)
    if (report.rows[i].error) points.push_back({i, report.rows[i].timings.total(), report.rows[i].error->rmse8});
  if (points.empty()) return {};
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0, top = 0.0;
  for (const Point& p : points) {
    if (p.ms > 0.0) lo = std::min(lo, p.ms);
    hi = std::max(hi, p.ms);
    top = std::max(top, p.rmse8);
  }
  if (!std::isfinite(lo)) lo = hi = 1.0;
  // Half a decade of room each side; a row that took no measurable time sits on the left edge.
  lo = std::pow(10.0, std::floor(std::log10(lo) - 0.25));
  hi = std::pow(10.0, std::ceil(std::log10(hi) + 0.25));
  const std::vector<double> yTicks = niceTicks(0.0, top > 0.0 ? top * 1.05 : 1.0, 6, true);
  Plot plot({lo, hi, true}, {0.0, maxOr(yTicks, 1.0), false});

  std::vector<Point> sorted = points;
  std::sort(sorted.begin(), sorted.end(),
            [](const Point& a, const Point& b) { return a.ms != b.ms ? a.ms < b.ms : a.rmse8 < b.rmse8; });
  std::string front;
  double best = std::numeric_limits<double>::infinity();
  for (const Point& p : sorted)
    if (p.rmse8 < best) {
      best = p.rmse8;
      front += fmt::format("{},{} ", coord(plot.x(std::max(p.ms, lo))), coord(plot.y(p.rmse8)));
    }
  plot.body += fmt::format("<polyline class=\"front\" points=\"{}\"/>\n", front);
  for (const Point& p : points) {
    const ReportRow& row = report.rows[p.row];
    const double px = plot.x(std::max(p.ms, lo)), py = plot.y(p.rmse8);
    const bool rightHalf = px > 0.5 * (Plot::kLeft + Plot::kWidth - Plot::kRight);  // label towards the middle
    plot.body += fmt::format(
        "<g class=\"series\" data-series=\"{0}\"><circle class=\"point\" data-technique=\"{1}\" data-ms=\"{2}\" "
        "data-rmse8=\"{3}\" cx=\"{4}\" cy=\"{5}\" r=\"5\" fill=\"{6}\"><title>{1}: RMSE8 {7}, {8} ms</title></circle>"
        "<text class=\"point-label\" x=\"{9}\" y=\"{10}\" text-anchor=\"{11}\">{1}</text></g>\n",
        p.row, esc(row.shownName()), exact(p.ms), exact(p.rmse8), coord(px), coord(py), techniqueColor(p.row),
        fixed(p.rmse8, 2), fixed(p.ms, 3), coord(rightHalf ? px - 7 : px + 7), coord(py - 7),
        rightHalf ? "end" : "start");
  }
  return plot.frame("plot-error-time", "RMSE8 against total time per frame", "prepare + visibility, ms (log scale)",
                    "RMSE8", logTicks(lo, hi), yTicks);
}

std::string mapSizePlot(const Report& report) {
  if (report.mapSizes.empty()) return {};
  double top = 0.0;
  for (const ReportRow& row : report.rows)
    for (const MapSizePoint& p : row.mapSizeSweep) top = std::max(top, p.error.rmse8);
  const double lo = *std::min_element(report.mapSizes.begin(), report.mapSizes.end());
  const double hi = *std::max_element(report.mapSizes.begin(), report.mapSizes.end());
  const double pad = hi > lo ? 0.15 * std::log(hi / lo) : std::log(2.0);
  const std::vector<double> yTicks = niceTicks(0.0, top > 0.0 ? top * 1.05 : 1.0, 6, true);
  Plot plot({lo * std::exp(-pad), hi * std::exp(pad), true}, {0.0, maxOr(yTicks, 1.0), false});
  for (size_t i = 0; i < report.rows.size(); ++i) {
    const ReportRow& row = report.rows[i];
    if (row.mapSizeSweep.size() != report.mapSizes.size()) continue;
    std::string line, marks;
    for (const MapSizePoint& p : row.mapSizeSweep) {
      const double px = plot.x(p.mapSize), py = plot.y(p.error.rmse8);
      line += fmt::format("{},{} ", coord(px), coord(py));
      if (row.mapSizeVaries)
        marks += fmt::format(
            "<circle class=\"point\" data-technique=\"{}\" data-map-size=\"{}\" data-rmse8=\"{}\" "
            "cx=\"{}\" cy=\"{}\" r=\"4\" fill=\"{}\"><title>{}: RMSE8 {} at {}&#178;</title></circle>",
            esc(row.shownName()), p.mapSize, exact(p.error.rmse8), coord(px), coord(py), techniqueColor(i),
            esc(row.shownName()), fixed(p.error.rmse8, 2), p.mapSize);
    }
    plot.body += fmt::format(
        "<g class=\"series\" data-series=\"{}\"><polyline class=\"{}\" stroke=\"{}\" points=\"{}\">"
        "<title>{}</title></polyline>{}</g>\n",
        i, row.mapSizeVaries ? "line" : "line flat", techniqueColor(i), line,
        esc(row.shownName() + (row.mapSizeVaries ? "" : " (no shadow map: one run)")), marks);
  }
  std::vector<double> ticks(report.mapSizes.begin(), report.mapSizes.end());
  return plot.frame("plot-map-size", "RMSE8 against shadow-map size", "shadow-map size, texels per side (log scale)",
                    "RMSE8", ticks, yTicks);
}

// Columns [first, last) of the plotted part of the profile.
struct ColumnRange {
  size_t first = 0, last = 0;
};

std::string profilePolyline(const Plot& plot, const std::vector<float>& values, const ColumnRange& range) {
  std::string points;
  for (size_t x = range.first; x < range.last && x < values.size(); ++x)
    points += fmt::format("{},{} ", coord(plot.x(static_cast<double>(x) + 0.5)),
                          coord(plot.y(roundedProfileValue(values[x]))));
  return points;
}

// The columns where the truth or any technique is not fully lit, with a margin of a quarter of
// their span each side (at least 8 pixels): a thin penumbra on a wide image would otherwise be a
// few pixels of the plot. The whole row when everything is lit.
ColumnRange shadowedColumns(const Report& report) {
  const ScanProfile& profile = *report.profile;
  const size_t width = profile.reference.size();
  size_t lo = width, hi = 0;
  auto scan = [&](const std::vector<float>& values) {
    for (size_t x = 0; x < values.size(); ++x)
      if (values[x] < 1.0f) {
        lo = std::min(lo, x);
        hi = std::max(hi, x + 1);
      }
  };
  scan(profile.reference);
  for (const ReportRow& row : report.rows)
    if (row.profile.size() == width) scan(row.profile);
  if (lo >= hi) return {0, width};
  const size_t margin = std::max<size_t>(8, (hi - lo) / 4);
  return {lo > margin ? lo - margin : 0, std::min(width, hi + margin)};
}

std::string profilePlot(const Report& report) {
  if (!report.profile) return {};
  const ScanProfile& profile = *report.profile;
  const ColumnRange range = shadowedColumns(report);
  const double first = static_cast<double>(range.first), last = static_cast<double>(range.last);
  Plot plot({first, last, false}, {0.0, 1.0, false});
  // Pixels outside the error mask (sky, surfaces facing away): shaded, since no error is measured there.
  for (size_t x = range.first; x < range.last && x < profile.mask.size();) {
    if (profile.mask[x]) {
      ++x;
      continue;
    }
    size_t end = x;
    while (end < range.last && end < profile.mask.size() && !profile.mask[end]) ++end;
    plot.body += fmt::format("<rect class=\"unmasked\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/>\n",
                             coord(plot.x(static_cast<double>(x))), coord(Plot::kTop),
                             coord(plot.x(static_cast<double>(end)) - plot.x(static_cast<double>(x))),
                             coord(Plot::kHeight - Plot::kTop - Plot::kBottom));
    x = end;
  }
  for (size_t i = 0; i < report.rows.size(); ++i) {
    const ReportRow& row = report.rows[i];
    if (row.profile.size() != profile.reference.size()) continue;
    plot.body += fmt::format(
        "<g class=\"series\" data-series=\"{}\"><polyline class=\"line\" data-technique=\"{}\" "
        "stroke=\"{}\" points=\"{}\"><title>{}</title></polyline></g>\n",
        i, esc(row.shownName()), techniqueColor(i), profilePolyline(plot, row.profile, range), esc(row.shownName()));
  }
  plot.body += fmt::format(
      "<g class=\"series\" data-series=\"truth\"><polyline class=\"line truth\" "
      "data-technique=\"truth\" stroke=\"{}\" points=\"{}\"><title>reference (truth)</title>"
      "</polyline></g>\n",
      kTruthColor, profilePolyline(plot, profile.reference, range));
  return plot.frame("plot-profile", fmt::format("V along image row {}", profile.row),
                    fmt::format("image column, row {} (columns {} to {} of {})", profile.row, range.first,
                                range.last - 1, profile.reference.size()),
                    "visibility V", niceTicks(first, last, 8), niceTicks(0.0, 1.0, 5));
}

std::string errorLegend(double range) {
  constexpr double kW = 360, kH = 46, kBar = 14, kPad = 20;
  std::string s = fmt::format(
      "<svg id=\"error-legend\" class=\"legend-bar\" viewBox=\"0 0 {} {}\" "
      "xmlns=\"http://www.w3.org/2000/svg\" role=\"img\" aria-label=\"signed error colour map\">"
      "<defs><linearGradient id=\"diverging\" x1=\"0\" x2=\"1\" y1=\"0\" y2=\"0\">",
      kW, kH);
  for (const auto& [t, c] : divergingStops())
    s += fmt::format("<stop offset=\"{:g}\" stop-color=\"{}\"/>", 0.5 * (t + 1.0), hex(c));
  s += fmt::format(
      "</linearGradient></defs><rect x=\"{}\" y=\"4\" width=\"{}\" height=\"{}\" fill=\"url(#diverging)\" "
      "stroke=\"#888\" stroke-width=\"0.5\"/>",
      kPad, kW - 2 * kPad, kBar);
  for (double t : {-1.0, -0.5, 0.0, 0.5, 1.0}) {
    const double px = kPad + 0.5 * (t + 1.0) * (kW - 2 * kPad);
    const double value = t * range;
    s += fmt::format(
        "<line x1=\"{0}\" x2=\"{0}\" y1=\"{1}\" y2=\"{2}\" stroke=\"#333\"/><text class=\"tick\" "
        "x=\"{0}\" y=\"{3}\" text-anchor=\"middle\">{4}</text>",
        coord(px), 4 + kBar, 8 + kBar, 22 + kBar, value == 0.0 ? "0" : fmt::format("{:+g}", value));
  }
  return s + "</svg>";
}

// ---- page --------------------------------------------------------------------------------------

const char* kStyle = R"css(
:root { color-scheme: light; --fg: #1b1b1b; --muted: #5c5c5c; --line: #d6d6d6; --bg: #fff; --panel: #f6f6f4; }
* { box-sizing: border-box; }
body { margin: 0; font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif; color: var(--fg); background: var(--bg); }
header, main { max-width: 1400px; margin: 0 auto; padding: 0 20px; }
header { padding-top: 18px; }
h1 { font-size: 22px; margin: 0 0 4px; } h2 { font-size: 18px; margin: 28px 0 8px; border-bottom: 1px solid var(--line); padding-bottom: 4px; }
h3 { font-size: 15px; margin: 0 0 6px; }
.muted { color: var(--muted); }
td.not-run { color: var(--muted); font-style: italic; }
code { font: 12px/1.4 ui-monospace, "DejaVu Sans Mono", monospace; background: var(--panel); padding: 1px 4px; border-radius: 3px; }
dl.setup { display: grid; grid-template-columns: max-content 1fr; gap: 3px 14px; margin: 0; }
dl.setup dt { color: var(--muted); } dl.setup dd { margin: 0; overflow-wrap: anywhere; }
table#results { border-collapse: collapse; width: 100%; font-variant-numeric: tabular-nums; }
#results th, #results td { padding: 5px 8px; border-bottom: 1px solid var(--line); text-align: right; vertical-align: top; }
#results th:first-child, #results td:first-child, #results td.params { text-align: left; }
#results td.params { font-size: 12px; color: var(--muted); max-width: 420px; }
#results th button { all: unset; cursor: pointer; font-weight: 600; white-space: nowrap; }
#results th button:focus-visible { outline: 2px solid #0072b2; }
#results th[aria-sort="ascending"] button::after { content: " \25B2"; }
#results th[aria-sort="descending"] button::after { content: " \25BC"; }
#results tbody tr:hover { background: var(--panel); }
.swatch { display: inline-block; width: 10px; height: 10px; border-radius: 2px; margin-right: 6px; vertical-align: baseline; }
.plots { display: grid; grid-template-columns: repeat(auto-fit, minmax(520px, 1fr)); gap: 16px; }
.plots figure { margin: 0; background: var(--panel); padding: 10px; border-radius: 6px; }
svg.plot { width: 100%; height: auto; display: block; font-size: 12px; }
.plot-bg { fill: #fff; stroke: #bbb; } .grid { stroke: #e4e4e4; } .tick { fill: #444; font-size: 11px; } .axis-label { fill: #222; font-size: 12px; }
.point { stroke: #fff; stroke-width: 1.2; } .point-label { font-size: 11px; fill: #222; }
.front { fill: none; stroke: #888; stroke-dasharray: 5 4; stroke-width: 1.2; }
.line { fill: none; stroke-width: 1.6; } .line.flat { stroke-dasharray: 6 4; } .line.truth { stroke-width: 2.6; }
.unmasked { fill: #ececec; }
.series.hidden { display: none; }
.legend { display: flex; flex-wrap: wrap; gap: 4px 14px; margin: 8px 0; }
.legend label { cursor: pointer; user-select: none; }
.cards { display: flex; flex-direction: column; gap: 18px; }
.card { background: var(--panel); border-radius: 6px; padding: 10px 12px; }
.card .row-images { display: grid; grid-template-columns: repeat(4, minmax(0, 1fr)); gap: 10px; }
.card.truth .row-images { grid-template-columns: repeat(4, minmax(0, 1fr)); }
figure.image { margin: 0; }
figure.image .frame { position: relative; line-height: 0; background: #222; }
figure.image img { width: 100%; height: auto; }
figure.image img.small { image-rendering: pixelated; }
figure.image figcaption { font-size: 12px; color: var(--muted); margin-top: 3px; }
.scanline { position: absolute; left: 0; right: 0; height: 0; border-top: 1px dashed rgba(255, 200, 0, 0.9); pointer-events: none; }
body.no-scanline .scanline { display: none; }
.legend-bar { width: 360px; max-width: 100%; height: auto; display: block; }
footer { max-width: 1400px; margin: 30px auto; padding: 0 20px; color: var(--muted); font-size: 12px; }
)css";

const char* kScript = R"js(
(function () {
  'use strict';
  // Table sorting: numbers by their unrounded data-value, text by locale; empty values sort last.
  const table = document.getElementById('results');
  if (table) {
    const headers = Array.from(table.tHead.rows[0].cells);
    headers.forEach((th, column) => {
      const button = th.querySelector('button');
      if (!button) return;
      button.addEventListener('click', () => {
        const ascending = th.getAttribute('aria-sort') !== 'ascending';
        headers.forEach((h) => h.removeAttribute('aria-sort'));
        th.setAttribute('aria-sort', ascending ? 'ascending' : 'descending');
        const numeric = th.dataset.type === 'number';
        const body = table.tBodies[0];
        const rows = Array.from(body.rows);
        const key = (row) => row.cells[column].dataset.value;
        rows.sort((a, b) => {
          const x = key(a), y = key(b);
          if (x === '' || y === '') return (x === '') - (y === '');
          const order = numeric ? Number(x) - Number(y) : x.localeCompare(y);
          return ascending ? order : -order;
        });
        rows.forEach((row) => body.appendChild(row));
      });
    });
  }
  // Legend check boxes show or hide a technique in every plot.
  document.querySelectorAll('.legend input[data-series]').forEach((box) => {
    box.addEventListener('change', () => {
      document.querySelectorAll('.series[data-series="' + box.dataset.series + '"]').forEach((g) => {
        g.classList.toggle('hidden', !box.checked);
      });
    });
  });
  // A sequence's frame slider: every image with data-frames shows that frame; play steps through them.
  const slider = document.getElementById('frame');
  if (slider) {
    const label = document.getElementById('frame-label');
    const count = Number(slider.max) + 1;
    const show = (k) => {
      slider.value = String(k);
      label.textContent = 'frame ' + (k + 1) + ' of ' + count;
      document.querySelectorAll('img[data-frames]').forEach((img) => {
        const file = img.dataset.frames.split('|')[k];
        if (file) img.setAttribute('src', file);
      });
    };
    slider.addEventListener('input', () => show(Number(slider.value)));
    const play = document.getElementById('play');
    let timer = null;
    play.addEventListener('click', () => {
      if (timer) {
        clearInterval(timer);
        timer = null;
        play.textContent = 'play';
        return;
      }
      play.textContent = 'pause';
      timer = setInterval(() => show((Number(slider.value) + 1) % count), 250);
    });
  }
  const scan = document.getElementById('show-scanline');
  if (scan) scan.addEventListener('change', () => document.body.classList.toggle('no-scanline', !scan.checked));
})();
)js";

// `frames`: for a sequence, the image's file at every frame (the frame slider swaps them).
std::string imageFigure(const std::string& file, const std::string& caption, const std::string& alt,
                        const Report& report, const std::vector<std::string>& frames = {}) {
  std::string line;
  if (report.profile && report.height > 0)
    line = fmt::format("<div class=\"scanline\" style=\"top: {:.4f}%\"></div>",
                       100.0 * (report.profile->row + 0.5) / report.height);
  // Small images are shown enlarged: square pixels then show what was computed, not a blur of it.
  const bool small = report.width <= 256 && report.height <= 256;
  return fmt::format(
      "<figure class=\"image\"><div class=\"frame\"><img src=\"{}\" alt=\"{}\" width=\"{}\" "
      "height=\"{}\"{}{}>{}</div><figcaption>{}</figcaption></figure>",
      esc(file), esc(alt), report.width, report.height, small ? " class=\"small\"" : "",
      frames.empty() ? std::string()
                     : fmt::format(" data-frames=\"{}\"", esc(fmt::format("{}", fmt::join(frames, "|")))),
      line, caption);
}

std::string findImage(const KeyValues& images, const std::string& kind) {
  for (const auto& [k, v] : images)
    if (k == kind) return v;
  return {};
}

// The file of `kind` at every frame of a row's sequence; empty when the row has none.
std::vector<std::string> frameImages(const ReportRow& row, const std::string& kind) {
  std::vector<std::string> files;
  if (!row.sequence) return files;
  for (const KeyValues& images : row.sequence->images) files.push_back(findImage(images, kind));
  return files;
}

std::string joinedParams(const KeyValues& params) {
  std::string s;
  for (const auto& [k, v] : params) s += fmt::format("{}{}={}", s.empty() ? "" : " ", k, v);
  return s;
}

std::string numberCell(std::optional<double> v, int precision) {
  if (!v || !std::isfinite(*v)) return "<td data-value=\"\">-</td>";
  return fmt::format("<td data-value=\"{}\">{}</td>", exact(*v), fixed(*v, precision));
}

std::string resultsTable(const Report& report) {
  const std::string ratioHeader = report.baseline.empty() ? "&#215; baseline" : "&#215; " + esc(report.baseline);
  std::string s = "<table id=\"results\"><thead><tr>";
  const std::pair<const char*, std::string> columns[] = {
      {"text", "technique"},     {"number", "RMSE8"},    {"number", "penumbra RMSE8"}, {"number", "max error"},
      {"number", "umbra leaks"}, {"number", "speckle"},  {"number", "prepare ms"},     {"number", "visibility ms"},
      {"number", "total ms"},    {"number", ratioHeader}};
  for (const auto& [type, name] : columns)
    s += fmt::format("<th data-type=\"{}\" scope=\"col\"><button type=\"button\">{}</button></th>", type,
                     type == std::string("text") ? esc(name) : name);
  s += "<th scope=\"col\">parameters</th></tr></thead>\n<tbody>\n";
  for (size_t i = 0; i < report.rows.size(); ++i) {
    const ReportRow& row = report.rows[i];
    s += fmt::format(
        "<tr data-technique=\"{0}\"><td data-value=\"{0}\"><span class=\"swatch\" style=\"background:{1}\">"
        "</span><a href=\"#card-{2}\">{0}</a></td>",
        esc(row.shownName()), techniqueColor(i), i);
    auto err = [&](auto member) -> std::optional<double> {
      if (!row.error) return std::nullopt;
      return static_cast<double>((*row.error).*member);
    };
    s += numberCell(err(&ErrorStats::rmse8), 2) + numberCell(err(&ErrorStats::penumbraRmse8), 2) +
         numberCell(err(&ErrorStats::maxAbsError), 3) + numberCell(err(&ErrorStats::umbraLeaks), 0) +
         numberCell(err(&ErrorStats::speckle), 0);
    s += numberCell(row.timings.get("prepare"), 2) + numberCell(row.timings.get("visibility"), 2) +
         numberCell(row.timings.total(), 2) + numberCell(row.ratioToBaseline, 2);
    s += fmt::format("<td class=\"params\">{}</td></tr>\n", esc(joinedParams(row.params)));
  }
  s += "</tbody>\n";
  // Techniques that could not take this scene keep a row, outside the sorted body, with the reason.
  if (!report.skipped.empty()) {
    s += "<tbody id=\"not-run\">\n";
    for (const auto& [name, why] : report.skipped)
      s += fmt::format(
          "<tr data-not-run=\"{0}\"><td>{0}</td><td colspan=\"{1}\" class=\"not-run\">not run here: {2}</td>"
          "</tr>\n",
          esc(name), std::size(columns), esc(why));
    s += "</tbody>\n";
  }
  return s + "</table>\n";
}

// Over a sequence: each row's error averaged over the frames and its temporal error, the truth's noise
// floor last (outside the sorted body).
std::string sequenceTable(const Report& report) {
  std::string s = "<table id=\"sequence\"><thead><tr>";
  for (const char* name : {"technique", "mean RMSE8", "mean penumbra RMSE8", "flicker", "pop %", "reversed pops %"})
    s += fmt::format("<th scope=\"col\">{}</th>", name);
  s += "</tr></thead>\n<tbody>\n";
  const auto temporalCells = [](const TemporalStats& t) {
    return numberCell(t.flicker, 2) + numberCell(100.0 * t.popRate, 2) + numberCell(100.0 * t.reversedPops, 1);
  };
  for (const ReportRow& row : report.rows) {
    if (!row.sequence || !row.error) continue;
    s += fmt::format("<tr data-technique=\"{0}\"><td data-value=\"{0}\">{0}</td>", esc(row.shownName())) +
         numberCell(row.error->rmse8, 2) + numberCell(row.error->penumbraRmse8, 2) +
         temporalCells(row.sequence->temporal) + "</tr>\n";
  }
  s += fmt::format("</tbody>\n<tbody><tr data-noise-floor><td>noise floor (reference, {})</td>",
                   esc(report.sequence->noiseFloorSeeds)) +
       numberCell(std::nullopt, 2) + numberCell(std::nullopt, 2) + temporalCells(report.sequence->noiseFloor) +
       "</tr></tbody>\n";
  return s + "</table>\n";
}

std::string seriesLegend(const Report& report) {
  std::string s = "<div class=\"legend\" id=\"series-legend\">";
  for (size_t i = 0; i < report.rows.size(); ++i)
    s += fmt::format(
        "<label><input type=\"checkbox\" checked data-series=\"{}\"><span class=\"swatch\" "
        "style=\"background:{}\"></span>{}</label>",
        i, techniqueColor(i), esc(report.rows[i].shownName()));
  if (report.profile)
    s += fmt::format(
        "<label><input type=\"checkbox\" checked data-series=\"truth\"><span class=\"swatch\" "
        "style=\"background:{}\"></span>reference (truth, profile only)</label>",
        kTruthColor);
  return s + "</div>\n";
}

}  // namespace

std::string reportToHtml(const Report& report) {
  std::string h =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  h += fmt::format("<title>penumbra {}: {}</title>\n<style>{}</style>\n</head>\n<body>\n", esc(report.kind),
                   esc(report.scene), kStyle);
  h += fmt::format(
      "<header><h1>penumbra {}: <code>{}</code></h1><p class=\"muted\">Every technique's visibility V "
      "against the ray-traced reference on the same G-buffer. RMSE8 = sqrt(mean((V &#8722; V<sub>ref</sub>)"
      "&#178;)) &#215; 255 over pixels facing the light; penumbra RMSE8 over those where V or V<sub>ref</sub>"
      " is in (0.01, 0.99); max error in V; umbra leaks: pixels the reference puts in the umbra "
      "(V<sub>ref</sub> &lt; 0.05) that the technique lights (V &gt; 0.5); speckle: pixels whose V is "
      "more than 0.25 from the median of its 3&#215;3 block where V<sub>ref</sub>'s is within 0.05 of its "
      "own. Times are medians of this run, on this machine; the ratio is to <code>{}</code> measured in the same "
      "run.</p></header>\n<main>\n",
      esc(report.kind), esc(report.scene), esc(report.baseline.empty() ? "-" : report.baseline));

  // Setup: enough to reproduce the report.
  h += "<section id=\"setup\"><h2>Setup</h2><dl class=\"setup\">\n";
  auto item = [&](const std::string& key, const std::string& valueHtml) {
    h += fmt::format("<dt>{}</dt><dd>{}</dd>\n", esc(key), valueHtml);
  };
  item("scene", fmt::format("<code>{}</code> ({})", esc(report.scene), esc(report.sceneSource)));
  item("light", fmt::format("{}: {}", report.lightIndex, esc(report.light)));
  item("image", fmt::format("{} &#215; {} pixels", report.width, report.height));
  if (report.truth)
    item("truth", fmt::format("<code>reference</code> {}{}", esc(joinedParams(report.truth->params)),
                              report.truth->cached ? " (read from the reference cache)" : ""));
  if (report.truth)
    for (const auto& [k, v] : report.truth->stats) item("truth " + k, esc(fmt::format("{:.6g}", v)));
  if (!report.baseline.empty()) item("time ratios to", fmt::format("<code>{}</code>", esc(report.baseline)));
  for (const auto& [k, v] : report.settings) item(k, esc(v));
  if (report.profile) item("scan line", fmt::format("row {} ({})", report.profile->row, esc(report.profile->choice)));
  item("penumbra version", esc(report.version));
  if (!report.command.empty()) item("reproduce", fmt::format("<code id=\"command\">{}</code>", esc(report.command)));
  std::string files;
  for (const auto& [kind, file] : report.files)
    files += fmt::format("{}<a href=\"{}\">{}</a> ({})", files.empty() ? "" : ", ", esc(file), esc(file), esc(kind));
  if (!files.empty()) item("files", files);
  h += "</dl></section>\n";

  h += "<section id=\"table\"><h2>Results</h2><p class=\"muted\">Click a column header to sort.</p>\n" +
       resultsTable(report);
  if (const std::vector<std::string> notes = reportNotes(report); !notes.empty()) {
    h += "<ul id=\"notes\">";
    for (const std::string& note : notes) h += "<li>" + esc(note) + "</li>";
    h += "</ul>";
  }
  h += "</section>\n";

  if (report.sequence)
    h += fmt::format(
        "<section id=\"over-sequence\"><h2>Over the sequence</h2><p class=\"muted\">{} frames, {}. Flicker = mean "
        "|&#916;V &#8722; &#916;V<sub>ref</sub>| &#215; 255 over the pixels in the penumbra (V or V<sub>ref</sub> in "
        "(0.01, 0.99)) of two consecutive frames, &#916; the change from one frame to the next; pop %: the share of "
        "those with |&#916;V &#8722; &#916;V<sub>ref</sub>| &gt; 0.1; reversed pops %: the share of pops undone at "
        "the next frame (shimmer). The noise floor is the truth against a truth of another seed. The table above "
        "averages each row's error over the frames.</p>\n{}</section>\n",
        report.sequence->frames, esc(report.sequence->motion), sequenceTable(report));

  h += "<section id=\"plots\"><h2>Plots</h2>\n" + seriesLegend(report) + "<div class=\"plots\">\n";
  if (const std::string p = errorTimePlot(report); !p.empty())
    h += "<figure><h3>Error against time</h3>" + p +
         "<figcaption class=\"muted\">Each technique a point; the dashed line joins those that no other technique "
         "beats in both time and error (the quality-per-millisecond front).</figcaption></figure>\n";
  if (const std::string p = mapSizePlot(report); !p.empty())
    h += "<figure><h3>Error against shadow-map size</h3>" + p +
         "<figcaption class=\"muted\">Dashed horizontal lines: techniques without a shadow map (one run, "
         "the same at every size).</figcaption></figure>\n";
  if (const std::string p = profilePlot(report); !p.empty())
    h += fmt::format(
        "<figure><h3>Scan-line profile</h3>{}<figcaption class=\"muted\">V along image row {} ({}); the "
        "reference (truth) is the thick black line; grey bands are pixels outside the error mask."
        "</figcaption></figure>\n",
        p, report.profile->row, esc(report.profile->choice));
  h += "</div></section>\n";

  // Images: the truth first, then each technique beside the truth's shaded image.
  h += "<section id=\"images\"><h2>Images</h2>\n";
  if (report.errorMapRange > 0.0)
    h += fmt::format(
        "<div class=\"error-legend\"><h3>Signed error V &#8722; V<sub>ref</sub></h3>{}<p class=\"muted\">"
        "Blue: darker than the reference (too much shadow); red: brighter (too little); white: equal. "
        "Symmetric range &#177;{:g} in V; larger errors saturate. Grey: not measured (outside the error "
        "mask).</p></div>\n",
        errorLegend(report.errorMapRange), report.errorMapRange);
  if (report.profile)
    h += fmt::format(
        "<p><label><input type=\"checkbox\" id=\"show-scanline\" checked> show the scan line (row {}) on "
        "the images</label></p>\n",
        report.profile->row);
  if (report.sequence)
    h += fmt::format(
        "<p class=\"frames\"><button type=\"button\" id=\"play\">play</button> <input type=\"range\" "
        "id=\"frame\" min=\"0\" max=\"{0}\" value=\"0\" aria-label=\"frame\"> <span id=\"frame-label\">frame 1 "
        "of {1}</span></p>\n",
        report.sequence->frames - 1, report.sequence->frames);
  h += "<div class=\"cards\">\n";
  const std::string truthShaded = report.truth ? findImage(report.truth->images, "shaded") : std::string();
  if (report.truth) {
    h += fmt::format(
        "<section class=\"card truth\" id=\"card-truth\"><h3>reference (truth): {}</h3><div "
        "class=\"row-images\">",
        esc(joinedParams(report.truth->params)));
    if (!truthShaded.empty())
      h += imageFigure(truthShaded, "shaded", "reference shaded", report, frameImages(*report.truth, "shaded"));
    if (const std::string v = findImage(report.truth->images, "visibility"); !v.empty())
      h += imageFigure(v, "visibility V", "reference visibility", report, frameImages(*report.truth, "visibility"));
    h += "</div></section>\n";
  }
  for (size_t i = 0; i < report.rows.size(); ++i) {
    const ReportRow& row = report.rows[i];
    if (row.images.empty()) continue;
    h += fmt::format(
        "<section class=\"card\" id=\"card-{}\"><h3><span class=\"swatch\" style=\"background:{}\"></span>"
        "{}{}</h3><div class=\"row-images\">",
        i, techniqueColor(i), esc(row.shownName()),
        row.error ? fmt::format(" <span class=\"muted\">RMSE8 {}, penumbra RMSE8 {}</span>", fixed(row.error->rmse8, 2),
                                fixed(row.error->penumbraRmse8, 2))
                  : std::string());
    if (!truthShaded.empty())
      h += imageFigure(truthShaded, "reference (truth), shaded", "reference shaded", report,
                       report.truth ? frameImages(*report.truth, "shaded") : std::vector<std::string>());
    const std::pair<const char*, const char*> kinds[] = {
        {"shaded", "shaded"}, {"visibility", "visibility V"}, {"error", "signed error V &#8722; V<sub>ref</sub>"}};
    for (const auto& [kind, caption] : kinds)
      if (const std::string file = findImage(row.images, kind); !file.empty())
        h += imageFigure(file, caption, row.shownName() + " " + kind, report, frameImages(row, kind));
    h += "</div></section>\n";
  }
  h += "</div></section>\n</main>\n";
  h += fmt::format("<footer>penumbra {}; every number on this page is in the JSON beside it.</footer>\n",
                   esc(report.version));
  h += fmt::format("<script>{}</script>\n</body>\n</html>\n", kScript);
  return h;
}

}  // namespace penumbra
