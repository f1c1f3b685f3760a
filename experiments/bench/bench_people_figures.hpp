#pragma once
// bench_people's figures (bench_people.cpp measures them,
// bench_people_report.cpp prints and writes them): its options, the recall
// bins, one case per detector and picture size, one per detector on real
// footage.
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "shared/config/robot_config.hpp"

namespace inspect::bench_people {

struct Options {
  std::vector<cv::Size> sizes{{320, 240}, {640, 480}};
  std::vector<std::string> wanted;
  std::string json_path, png_dir, video_path;
  int frames = 300, video_frames = 120, threads = 1;
  uint64_t seed = 1;
  double noise = 3.0, exposure_ms = 8.0, tilt_deg = 0.0;
  bool wide = false;                   // --head wide: config/robot.yaml's wide_camera, people at 0.6-6 m
  double hfov_deg = 0.0, z_m = 0.0;    // --hfov-deg / --z-m: the head's, changed (0 = as configured)
};

// Recall in bins of one quantity.
struct Bins {
  std::string name;
  std::vector<double> edges;  // bin i: [edges[i], edges[i+1])
  std::vector<std::string> labels;
  std::vector<int> found, total;
  void init() {
    found.assign(labels.size(), 0);
    total.assign(labels.size(), 0);
  }
  void add(double v, bool hit) {
    for (std::size_t i = 0; i + 1 < edges.size(); ++i)
      if (v >= edges[i] && v < edges[i + 1]) {
        ++total[i];
        if (hit) ++found[i];
        return;
      }
  }
};

struct Case {
  std::string detector, settings;
  int width = 0, height = 0, frames = 0;
  int truths = 0, found = 0, boxes = 0, false_boxes = 0;
  std::vector<double> bearing_err_deg, range_err_pct, range_signed_pct, ms;
  double cpu_ms = 0;
  Bins by_distance{"distance m", {1, 2, 3, 4, 6, 8, 11}, {"1-2", "2-3", "3-4", "4-6", "6-8", "8-10"}, {}, {}};
  Bins by_bearing{"|bearing| deg", {0, 10, 20, 40}, {"0-10", "10-20", "20-33"}, {}, {}};
  Bins by_visible{"visible", {0.3, 0.6, 0.9, 1.01}, {"30-60%", "60-90%", "90-100%"}, {}, {}};
  // The arena's detector model is calibrated from these two (sim/detector_model).
  Bins by_distance_clear{"distance m (90-100% visible)", {1, 2, 3, 4, 6, 8, 11}, {"1-2", "2-3", "3-4", "4-6", "6-8", "8-10"}, {}, {}};
  Bins by_distance_part{"distance m (30-90% visible)", {1, 2, 3, 4, 6, 8, 11}, {"1-2", "2-3", "3-4", "4-6", "6-8", "8-10"}, {}, {}};
  Bins by_view{"view", {0, 45, 135, 181}, {"front", "side", "back"}, {}, {}};
  Bins by_motion{"motion", {0, 0.1, 10}, {"standing", "walking"}, {}, {}};
  /// The wide head's bins: people from 0.6 m, bearings to 62 degrees.
  void useWideBins() {
    const std::vector<double> d{0.6, 1, 1.5, 2, 3, 4, 6.01};
    const std::vector<std::string> dl{"0.6-1", "1-1.5", "1.5-2", "2-3", "3-4", "4-6"};
    for (Bins* b : {&by_distance, &by_distance_clear, &by_distance_part}) {
      b->edges = d;
      b->labels = dl;
    }
    by_bearing.edges = {0, 15, 30, 45, 65};
    by_bearing.labels = {"0-15", "15-30", "30-45", "45-62"};
  }
  std::vector<Bins*> all() {
    return {&by_distance, &by_bearing, &by_visible, &by_view, &by_motion, &by_distance_clear, &by_distance_part};
  }
  double recall() const { return truths ? static_cast<double>(found) / truths : NAN; }
  double precision() const { return boxes ? static_cast<double>(boxes - false_boxes) / boxes : NAN; }
};

struct VideoCase {
  std::string detector;
  int width = 0, height = 0, frames = 0;
  double boxes_per_frame = 0, frames_with_box_pct = 0;
  std::vector<double> ms;
};

/// The q-quantile of v (nearest rank); NaN when v is empty.
double quantile(std::vector<double> v, double q);
/// The tables for people: the cases, recall by each bin, the signed range
/// error, the footage, and how each figure is made.
void printTables(const Options& o, const config::CameraMount& mount, std::vector<Case>& cases,
                 const std::vector<VideoCase>& vcases, const std::vector<std::string>& pngs);
/// The same figures as JSON (--json); false (printed why) when the file cannot be written.
bool writeJson(const Options& o, const config::CameraMount& mount, std::vector<Case>& cases,
               const std::vector<VideoCase>& vcases);

}  // namespace inspect::bench_people
