// Comparison reports: one row per technique (parameters, error against the reference, pass
// timings, time relative to a baseline measured in the same run, the technique's own stats) plus
// the scene, light, settings and version they came from; written as JSON (for scripts) and as
// Markdown / plain text tables (for people). `penumbra compare` and `penumbra bench` fill them.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "penumbra/light.h"
#include "penumbra/metrics.h"
#include "penumbra/params.h"
#include "penumbra/technique.h"

namespace penumbra {

using KeyValues = std::vector<std::pair<std::string, std::string>>;

struct ReportRow {
  std::string technique;
  KeyValues params;                  //!< resolved parameters, "auto" where the technique derives it
  std::optional<ErrorStats> error;   //!< against the reference; absent when not measured (bench)
  PassTimings timings;               //!< per pass, ms ("prepare", "visibility", ...)
  std::optional<double> ratioToBaseline;  //!< total ms / the baseline's total ms (fillBaselineRatios)
  std::vector<std::pair<std::string, double>> stats;  //!< ShadowTechnique::stats()
  KeyValues images;                  //!< kind -> file name, relative to the report's directory
};

struct Report {
  std::string kind;         //!< "compare" or "bench"
  std::string version;      //!< penumbra version
  std::string scene;        //!< scene name
  std::string sceneSource;  //!< "built-in:torus" or the file path
  int lightIndex = 0;
  std::string light;        //!< describeLight() of the light used
  int width = 0, height = 0;
  std::string baseline;     //!< technique the ratios are relative to; empty for none
  KeyValues settings;       //!< spp, seed, threads, repeat, G-buffer ms, ...
  std::vector<ReportRow> rows;
};

// One line naming the light's shape and its defining values, e.g. "sphere center (0, 4, 0) radius 0.5".
std::string describeLight(const Light& light);
// Resolved parameters as strings, by name ("auto" for values the technique derives).
KeyValues describeParams(const Params& params);
// Sets every row's ratioToBaseline from the row named report.baseline (left empty if it is absent
// or took no time).
void fillBaselineRatios(Report& report);

std::string reportToJson(const Report& report);
std::string reportToMarkdown(const Report& report);
// Aligned plain-text table for the terminal.
std::string reportToText(const Report& report);

// Writes text to path; throws Error naming the path when it cannot.
void writeTextFile(const std::string& path, const std::string& text);

}  // namespace penumbra
