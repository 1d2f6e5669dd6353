#include "evaluation_files.hpp"

#include "gnuplot.hpp"

#include <s2kf/io/atomic_file.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <ostream>
#include <sstream>

namespace s2kf::cli {
namespace {

namespace fs = std::filesystem;

void write_csv(const fs::path& path, const std::string& header, std::size_t rows,
               const std::function<void(std::ostream&, std::size_t)>& row) {
  io::write_file_atomically(path, [&](std::ostream& out) {
    out << header << "\n";
    for (std::size_t r = 0; r < rows; ++r) {
      row(out, r);
      out << "\n";
    }
  });
}

}  // namespace

std::string cell(double value) {
  if (!std::isfinite(value)) return "nan";
  std::ostringstream s;
  s << std::setprecision(7) << value;
  return s.str();
}

std::vector<std::string> write_evaluation_series(const fs::path& out, const EvaluationSeries& s) {
  // Named references, not a structured binding: C++17 lambdas may not capture bindings (Clang refuses).
  const double rate_hz = s.rate_hz;
  const std::size_t frames = s.frames;
  const auto& sweep = s.sweep;
  const auto& s2kf = s.s2kf;
  const auto& baseline = s.baseline;
  const auto& study = s.study;
  const bool with_truth = s.with_truth;
  auto time_of = [&](std::size_t f) { return static_cast<double>(f) / rate_hz; };
  std::vector<std::string> written;
  auto add = [&](const std::string& name) { written.push_back(name); };
  write_csv(out / "marker_distance.csv", "frame,time,s2kf_mm,baseline_mm", frames,
            [&](std::ostream& o, std::size_t f) {
              o << f << "," << cell(time_of(f)) << "," << cell(s2kf.run.mean_marker_distance[f]) << ","
                << cell(baseline.run.mean_marker_distance[f]);
            });
  add("marker_distance.csv");
  write_csv(
      out / "occlusion_band.csv",
      "frame,time,s2kf_min_mm,s2kf_max_mm,s2kf_mean_mm,baseline_min_mm,baseline_max_mm,baseline_mean_mm",
      frames, [&](std::ostream& o, std::size_t f) {
        o << f << "," << cell(time_of(f)) << "," << cell(study.s2kf.min[f]) << "," << cell(study.s2kf.max[f])
          << "," << cell(study.s2kf.mean[f]) << "," << cell(study.baseline.min[f]) << ","
          << cell(study.baseline.max[f]) << "," << cell(study.baseline.mean[f]);
      });
  add("occlusion_band.csv");
  const int examples = std::min(3, study.runs);
  std::string hidden_header = "frame,time";
  for (int r = 0; r < examples; ++r) hidden_header += ",run" + std::to_string(r + 1);
  write_csv(out / "hidden_markers.csv", hidden_header + ",mean", frames, [&](std::ostream& o, std::size_t f) {
    o << f << "," << cell(time_of(f));
    for (int r = 0; r < examples; ++r) o << "," << study.hidden[static_cast<std::size_t>(r)][f];
    o << "," << cell(study.mean_hidden[f]);
  });
  add("hidden_markers.csv");
  std::string runtime_header = "frame,time";
  for (const auto& r : sweep) runtime_header += ",s2kf_L" + std::to_string(r.samples) + "_ms";
  write_csv(out / "runtime.csv", runtime_header + ",baseline_ms", frames,
            [&](std::ostream& o, std::size_t f) {
              o << f << "," << cell(time_of(f));
              for (const auto& r : sweep) o << "," << cell(1000 * r.run.seconds[f]);
              o << "," << cell(1000 * baseline.run.seconds[f]);
            });
  add("runtime.csv");
  if (with_truth) {
    write_csv(out / "joint_error.csv", "frame,time,s2kf_deg,baseline_deg", frames,
              [&](std::ostream& o, std::size_t f) {
                o << f << "," << cell(time_of(f)) << "," << cell(s2kf.truth->per_frame_joint_rms_deg[f])
                  << "," << cell(baseline.truth->per_frame_joint_rms_deg[f]);
              });
    add("joint_error.csv");
  }
  write_csv(
      out / "samples.csv",
      "samples,median_ms,p99_ms,max_ms,mean_marker_distance_mm,converged_frame,segment_orientation_rms_deg,"
      "limb_flexion_rms_deg,all_joint_rms_deg",
      sweep.size(), [&](std::ostream& o, std::size_t k) {
        const auto& r = sweep[k];
        o << r.samples << "," << cell(r.median_ms) << "," << cell(r.p99_ms) << "," << cell(r.max_ms) << ","
          << cell(r.level_mm) << "," << r.converged_frame;
        for (double v :
             {r.truth ? r.truth->segment_orientation_rms_deg : NAN,
              r.truth ? r.truth->limb_flexion_rms_deg : NAN, r.truth ? r.truth->all_joint_rms_deg : NAN})
          o << "," << cell(v);
      });
  add("samples.csv");
  return written;
}

void draw_evaluation_figures(const fs::path& out, const EvaluationSeries& s,
                             std::vector<std::string>& written, std::vector<std::string>& problems) {
  const auto& sweep = s.sweep;
  const auto& study = s.study;
  const int examples = std::min(3, study.runs);  // runs drawn one by one in Fig. 7
  std::vector<std::string>& figure_problems = problems;
  auto add = [&](const std::string& name) { written.push_back(name); };
  const bool gnuplot = have_gnuplot();
  if (!gnuplot)
    figure_problems.push_back(
        "gnuplot is not installed (Debian: apt-get install gnuplot-nox): no figures were drawn; "
        "the CSV files hold every series");
  auto figure = [&](const std::string& name, const std::string& body) {
    std::string problem;
    if (!gnuplot) return;
    if (plot(out, name, body, problem)) {
      add(name + ".png");
      add(name + ".svg");
    } else {
      figure_problems.push_back(problem);
    }
  };
  const std::string L = std::to_string(s.s2kf.samples);
  figure(
      "fig3_marker_distance",
      "  set title 'Average marker distance per frame (paper Fig. 3)'\n"
      "  set xlabel 'frame'; set ylabel 'mean marker distance (mm)'\n"
      "  plot 'occlusion_band.csv' using 1:3:4 with filledcurves fs transparent solid 0.3 lc rgb '#1f77b4' "
      "title 'S2KF with occlusion, min-max over " +
          std::to_string(study.runs) +
          " runs', \\\n"
          "       'occlusion_band.csv' using 1:5 with lines lw 1 dt 2 lc rgb '#1f77b4' title 'S2KF with "
          "occlusion, mean', \\\n"
          "       'marker_distance.csv' using 1:3 with lines lw 2 lc rgb '#ff7f0e' title 'S2KF (L = " +
          L +
          ")', \\\n"
          "       'marker_distance.csv' using 1:4 with lines lw 2 lc rgb '#2ca02c' title 'gradient "
          "baseline'");
  std::string runtime_plot =
      "  set title 'Runtime per frame (paper Fig. 4)'\n"
      "  set xlabel 'frame'; set ylabel 'ms'; set logscale y\n  plot ";
  for (std::size_t k = 0; k < sweep.size(); ++k)
    runtime_plot += "'runtime.csv' using 1:" + std::to_string(3 + k) +
                    " with lines title 'S2KF L = " + std::to_string(sweep[k].samples) + "', ";
  runtime_plot += "'runtime.csv' using 1:" + std::to_string(3 + sweep.size()) +
                  " with lines lc rgb '#2ca02c' title 'gradient baseline'\n  unset logscale y";
  figure("fig4_runtime", runtime_plot);
  std::string hidden_plot =
      "  set title 'Hidden markers per frame (paper Fig. 7)'\n"
      "  set xlabel 'frame'; set ylabel 'hidden markers'\n  plot ";
  for (int r = 0; r < examples; ++r)
    hidden_plot += "'hidden_markers.csv' using 1:" + std::to_string(3 + r) + " with lines title 'run " +
                   std::to_string(r + 1) + "', ";
  hidden_plot += "'hidden_markers.csv' using 1:" + std::to_string(3 + examples) +
                 " with lines lw 2 lc rgb 'black' title 'mean over " + std::to_string(study.runs) + " runs'";
  figure("fig7_hidden_markers", hidden_plot);
  if (s.with_truth)
    figure("joint_error",
           "  set title 'Joint-angle error against the truth (RMS over the 40 joints, after a " +
               std::to_string(s.warmup) +
               "-frame warm-up)'\n"
               "  set xlabel 'frame'; set ylabel 'degrees'\n"
               "  plot 'joint_error.csv' using 1:3 with lines lw 2 lc rgb '#ff7f0e' title 'S2KF (L = " +
               L +
               ")', 'joint_error.csv' using 1:4 with lines lw 2 lc rgb '#2ca02c' title 'gradient baseline'");
  figure("samples",
         "  set multiplot layout 1,2 title 'S2KF against the sample count L'\n"
         "  set xlabel 'samples L'; set ylabel 'latency per frame (ms)'; set key top left\n"
         "  plot 'samples.csv' using 1:2 with linespoints title 'median', 'samples.csv' using 1:3 with "
         "linespoints "
         "title 'p99'\n"
         "  set ylabel 'error'; set key center right  # between the distance and the segment curves\n"
         "  plot 'samples.csv' using 1:5 with linespoints title 'marker distance (mm)', 'samples.csv' using "
         "1:7 with "
         "linespoints title 'segment orientation RMS (deg)', 'samples.csv' using 1:9 with linespoints title "
         "'all-joint RMS (deg)'\n"
         "  unset multiplot");
}

}  // namespace s2kf::cli
