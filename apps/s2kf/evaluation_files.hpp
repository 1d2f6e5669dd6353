/// @file
/// The files `s2kf evaluate` writes beside its summary.json: the CSV series (marker distance,
/// occlusion band, hidden markers, runtime, joint error, sample sweep) and the gnuplot figures
/// drawn from them (the paper's Figs. 3, 4 and 7, the joint error, the sample sweep).
#pragma once

#include <s2kf/evaluation/evaluation.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace s2kf::cli {

/// What one evaluation measured, as its files need it (references into the caller's results).
struct EvaluationSeries {
  double rate_hz;
  std::size_t frames;
  const std::vector<evaluation::MethodResult>& sweep;  ///< the S2KF at each sample count
  const evaluation::MethodResult& s2kf;                ///< the comparison's S2KF (one of `sweep`)
  const evaluation::MethodResult& baseline;
  const evaluation::OcclusionStudy& study;
  bool with_truth;  ///< the methods have per-frame joint errors
  long warmup;      ///< frames left out of the accuracy against the truth
};

/// A number as the CSV series and the printed lines write it (7 significant digits, "nan").
std::string cell(double value);

/// Writes the CSV series into `out` (which exists); returns their file names.
std::vector<std::string> write_evaluation_series(const std::filesystem::path& out, const EvaluationSeries& s);

/// Draws the figures from the series in `out` with gnuplot, as PNG and SVG; adds the files drawn to
/// `written` and a sentence per figure that could not be drawn (or one when gnuplot is missing) to
/// `problems`.
void draw_evaluation_figures(const std::filesystem::path& out, const EvaluationSeries& s,
                             std::vector<std::string>& written, std::vector<std::string>& problems);

}  // namespace s2kf::cli
