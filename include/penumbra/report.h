// Comparison reports: one row per technique (parameters, error against the reference, pass
// timings, time relative to a baseline measured in the same run, the technique's own stats) plus
// the scene, light, settings and version they came from; written as JSON (for scripts), as
// Markdown / plain text tables (for people) and as a self-contained HTML page (images beside it,
// a sortable table, SVG plots of error against time, against shadow-map size and along a scan
// line). `penumbra compare` and `penumbra bench` fill them.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "penumbra/light.h"
#include "penumbra/metrics.h"
#include "penumbra/params.h"
#include "penumbra/technique.h"
#include "penumbra/temporal_metrics.h"

namespace penumbra {

using KeyValues = std::vector<std::pair<std::string, std::string>>;

// One run of a technique at one shadow-map size (`penumbra compare --map-sizes`).
struct MapSizePoint {
  int mapSize = 0;  //!< texels per side
  ErrorStats error;
  PassTimings timings;
};

// A row's numbers over the frames of a sequence (`penumbra compare` on a scene with a motion).
struct SequenceRow {
  std::vector<ErrorStats> frames;  //!< per frame, against that frame's truth
  TemporalStats temporal;          //!< against the truth's sequence
  std::vector<KeyValues> images;   //!< per frame: kind -> file name, as ReportRow::images
};

struct ReportRow {
  std::string technique;
  std::string label;                      //!< shown name, e.g. "reference (16 spp)"; empty: the technique's name
  KeyValues params;                       //!< resolved parameters, "auto" where the technique derives it
  std::optional<ErrorStats> error;        //!< against the reference; absent when not measured (bench)
  PassTimings timings;                    //!< per pass, ms ("prepare", "visibility", ...)
  std::optional<double> ratioToBaseline;  //!< total ms / the baseline's total ms (fillBaselineRatios)
  std::vector<std::pair<std::string, double>> stats;  //!< ShadowTechnique::stats()
  KeyValues images;                                   //!< kind -> file name, relative to the report's directory
  std::vector<float> profile;                         //!< V along Report::profile's row (empty: none)
  // Error per shadow-map size, in Report::mapSizes' order. mapSizeVaries false: the technique has
  // no map_size parameter, so one run stands for every size (the same point repeated).
  std::vector<MapSizePoint> mapSizeSweep;
  bool mapSizeVaries = false;
  bool cached = false;  //!< V was read from the reference cache, not rendered in this run
  // Set for a sequence: `error` is then the mean over frames (maxima for max err), `timings` the
  // median of each pass over frames, `images` the first frame's.
  std::optional<SequenceRow> sequence;

  const std::string& shownName() const { return label.empty() ? technique : label; }
};

// What moved in a sequence, and the truth's own temporal noise.
struct SequenceInfo {
  int frames = 0;
  std::string motion;           //!< e.g. "light 0 along (0.5, 8, -1) -> (0.7, 8, -1)"
  TemporalStats noiseFloor;     //!< the truth against a truth of another seed, frame by frame
  std::string noiseFloorSeeds;  //!< e.g. "seeds 1 and 2"
};

// V along one image row: where the penumbrae of the techniques can be seen side by side.
struct ScanProfile {
  int row = 0;                   //!< image row, 0 = top
  std::string choice;            //!< how the row was chosen ("--profile-row", "most penumbra pixels ...")
  std::vector<float> reference;  //!< the truth's V along the row
  std::vector<uint8_t> mask;     //!< 1 where the pixel is in the error mask
};

struct Report {
  std::string kind;         //!< "compare" or "bench"
  std::string version;      //!< penumbra version
  std::string scene;        //!< scene name
  std::string sceneSource;  //!< "built-in:torus" or the file path
  int lightIndex = 0;
  std::string light;  //!< describeLight() of the light used
  int width = 0, height = 0;
  std::string baseline;  //!< technique the ratios are relative to; empty for none
  KeyValues settings;    //!< spp, seed, threads, repeat, G-buffer ms, ...
  std::vector<ReportRow> rows;

  // compare only:
  std::optional<ReportRow> truth;  //!< the reference every row's error is measured against
  std::vector<int> mapSizes;       //!< --map-sizes; empty: no sweep
  std::optional<ScanProfile> profile;
  double errorMapRange = 0.0;            //!< error maps span V - V_ref in [-range, range]; 0: none drawn
  std::string command;                   //!< a command line that reproduces the report
  KeyValues files;                       //!< other files beside the report: kind -> file name
  KeyValues skipped;                     //!< technique -> why it did not run (e.g. a light shape it does not support)
  std::optional<SequenceInfo> sequence;  //!< set when the rows are over the frames of a motion
};

// One line naming the light's shape and its defining values, e.g. "sphere center (0, 4, 0) radius 0.5".
std::string describeLight(const Light& light);
// Resolved parameters as strings, by name ("auto" for values the technique derives).
KeyValues describeParams(const Params& params);
// Sets every row's ratioToBaseline from the row named report.baseline (left empty if it is absent
// or took no time).
void fillBaselineRatios(Report& report);

// What a reader must know to compare the rows fairly, one sentence each: where a row did not see the
// same geometry as the reference (parker's true spheres: its `analytic_spheres` stat). Every writer
// prints them.
std::vector<std::string> reportNotes(const Report& report);

// A scan-line profile value as reports write it: V rounded to 1e-4 (JSON and page alike).
double roundedProfileValue(float v);

std::string reportToJson(const Report& report);
std::string reportToMarkdown(const Report& report);
// Aligned plain-text table for the terminal.
std::string reportToText(const Report& report);
// A self-contained page: no network, images referenced by the file names in ReportRow::images
// (beside the page). Every number it shows is in reportToJson's output: table cells carry the
// unrounded value in data-value, plots are drawn from the same values.
std::string reportToHtml(const Report& report);

// Writes text to path; throws Error naming the path when it cannot.
void writeTextFile(const std::string& path, const std::string& text);

}  // namespace penumbra
