// bench_people's tables and JSON (the figures of bench_people.cpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "experiments/bench/bench_people_figures.hpp"

namespace inspect::bench_people {

namespace {

nlohmann::ordered_json numberOrNull(double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nullptr; }

std::string cell(double v, const char* fmt) {
  if (!std::isfinite(v)) return "-";
  char b[32];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

}  // namespace

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5))];
}

void printTables(const Options& o, const config::CameraMount& mount, std::vector<Case>& cases,
                 const std::vector<VideoCase>& vcases, const std::vector<std::string>& pngs) {
  std::printf("bench_people: %d pictures per case, seed %llu, noise %.1f grey levels, exposure %.0f ms; worlds warehouse,\n"
              "narrow_aisle, gas_lab, square_room; %s head %.0f deg wide at %.2f m, tilt %+.0f deg; people at %s m;\n"
              "OpenCV threads %d\n\n",
              o.frames, static_cast<unsigned long long>(o.seed), o.noise, o.exposure_ms, o.wide ? "wide" : "PTZ",
              mount.hfov_deg, mount.z_m, mount.tilt_deg + o.tilt_deg, o.wide ? "0.6-6" : "1-10", o.threads);
  std::printf("| size | detector | people | recall | precision | false / picture | bearing err p50 / p90 deg | "
              "range err p50 / p90 %% | ms p50 / p90 | CPU ms |\n|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& c : cases)
    std::printf("| %dx%d | %s | %d | %s | %s | %s | %s / %s | %s / %s | %s / %s | %.1f |\n", c.width, c.height,
                c.detector.c_str(), c.truths, cell(100 * c.recall(), "%.1f %%").c_str(),
                cell(100 * c.precision(), "%.1f %%").c_str(),
                cell(static_cast<double>(c.false_boxes) / std::max(1, c.frames), "%.3f").c_str(),
                cell(quantile(c.bearing_err_deg, 0.5), "%.2f").c_str(), cell(quantile(c.bearing_err_deg, 0.9), "%.2f").c_str(),
                cell(quantile(c.range_err_pct, 0.5), "%.1f").c_str(), cell(quantile(c.range_err_pct, 0.9), "%.1f").c_str(),
                cell(quantile(c.ms, 0.5), "%.1f").c_str(), cell(quantile(c.ms, 0.9), "%.1f").c_str(), c.cpu_ms);
  if (!cases.empty()) {
    Case& first = cases.front();
    for (std::size_t b = 0; b < first.all().size(); ++b) {
      const Bins& head = *first.all()[b];
      std::printf("\nrecall by %s (found / people)\n| size | detector |", head.name.c_str());
      for (const auto& l : head.labels) std::printf(" %s |", l.c_str());
      std::printf("\n|---|---|");
      for (std::size_t i = 0; i < head.labels.size(); ++i) std::printf("---|");
      std::printf("\n");
      for (auto& c : cases) {
        const Bins& bn = *c.all()[b];
        std::printf("| %dx%d | %s |", c.width, c.height, c.detector.c_str());
        for (std::size_t i = 0; i < bn.labels.size(); ++i)
          std::printf(" %s (%d/%d) |", cell(bn.total[i] ? 100.0 * bn.found[i] / bn.total[i] : NAN, "%.0f %%").c_str(),
                      bn.found[i], bn.total[i]);
        std::printf("\n");
      }
    }
  }
  std::printf("\nrange from the foot row, signed (long > 0): p10 / p50 / p90 %%\n| size | detector | p10 | p50 | p90 |\n"
              "|---|---|---|---|---|\n");
  for (const auto& c : cases)
    std::printf("| %dx%d | %s | %s | %s | %s |\n", c.width, c.height, c.detector.c_str(),
                cell(quantile(c.range_signed_pct, 0.1), "%+.1f").c_str(),
                cell(quantile(c.range_signed_pct, 0.5), "%+.1f").c_str(),
                cell(quantile(c.range_signed_pct, 0.9), "%+.1f").c_str());
  if (!vcases.empty()) {
    std::printf("\nreal footage: %s (%d frames; no truth: boxes per frame, frames with a box)\n"
                "| size | detector | boxes / frame | frames with a box | ms p50 / p90 |\n|---|---|---|---|---|\n",
                o.video_path.c_str(), vcases.front().frames);
    for (const auto& v : vcases)
      std::printf("| %dx%d | %s | %.2f | %.1f %% | %.1f / %.1f |\n", v.width, v.height, v.detector.c_str(), v.boxes_per_frame,
                  v.frames_with_box_pct, quantile(v.ms, 0.5), quantile(v.ms, 0.9));
  }
  std::printf("\nrecall = people found / people at least 30 %% visible (IoU >= 0.3 with the figure's box; upper-body\n"
              "boxes against its top 35 %%). bearing err: box centre column through the intrinsics against the\n"
              "body axis. range err: the box's bottom row as the feet on a flat floor (lens height, horizon)\n"
              "against the true distance, where the feet are in the picture.\n");
  for (const auto& p : pngs) std::printf("picture: %s\n", p.c_str());
}

bool writeJson(const Options& o, const config::CameraMount& mount, std::vector<Case>& cases,
               const std::vector<VideoCase>& vcases) {
  nlohmann::ordered_json j;
  j["pictures_per_case"] = o.frames;
  j["seed"] = o.seed;
  j["noise_sigma"] = o.noise;
  j["exposure_ms"] = o.exposure_ms;
  j["head"] = o.wide ? "wide" : "ptz";
  j["hfov_deg"] = mount.hfov_deg;
  j["z_m"] = mount.z_m;
  j["mount_tilt_deg"] = mount.tilt_deg;
  j["tilt_deg"] = o.tilt_deg;
  j["opencv_threads"] = o.threads;
  auto& jc = j["cases"];
  jc = nlohmann::ordered_json::array();
  for (auto& c : cases) {
    nlohmann::ordered_json e{{"size", std::to_string(c.width) + "x" + std::to_string(c.height)},
                             {"detector", c.detector},
                             {"settings", c.settings},
                             {"people", c.truths},
                             {"found", c.found},
                             {"boxes", c.boxes},
                             {"false_boxes", c.false_boxes},
                             {"recall", numberOrNull(c.recall())},
                             {"precision", numberOrNull(c.precision())},
                             {"false_per_picture", static_cast<double>(c.false_boxes) / std::max(1, c.frames)},
                             {"bearing_err_deg_p50", numberOrNull(quantile(c.bearing_err_deg, 0.5))},
                             {"bearing_err_deg_p90", numberOrNull(quantile(c.bearing_err_deg, 0.9))},
                             {"range_err_pct_p50", numberOrNull(quantile(c.range_err_pct, 0.5))},
                             {"range_err_pct_p90", numberOrNull(quantile(c.range_err_pct, 0.9))},
                             {"range_signed_pct_p10", numberOrNull(quantile(c.range_signed_pct, 0.1))},
                             {"range_signed_pct_p50", numberOrNull(quantile(c.range_signed_pct, 0.5))},
                             {"range_signed_pct_p90", numberOrNull(quantile(c.range_signed_pct, 0.9))},
                             {"ms_p50", numberOrNull(quantile(c.ms, 0.5))},
                             {"ms_p90", numberOrNull(quantile(c.ms, 0.9))},
                             {"cpu_ms", c.cpu_ms}};
    for (auto* b : c.all()) {
      auto& jb = e["recall_by_" + b->name];
      for (std::size_t i = 0; i < b->labels.size(); ++i)
        jb[b->labels[i]] = {{"found", b->found[i]}, {"people", b->total[i]}};
    }
    jc.push_back(std::move(e));
  }
  auto& jv = j["video"];
  jv = nlohmann::ordered_json::array();
  for (const auto& v : vcases)
    jv.push_back({{"file", o.video_path},
                  {"size", std::to_string(v.width) + "x" + std::to_string(v.height)},
                  {"detector", v.detector},
                  {"frames", v.frames},
                  {"boxes_per_frame", v.boxes_per_frame},
                  {"frames_with_box_pct", v.frames_with_box_pct},
                  {"ms_p50", numberOrNull(quantile(v.ms, 0.5))},
                  {"ms_p90", numberOrNull(quantile(v.ms, 0.9))}});
  std::ofstream out(o.json_path);
  out << j.dump(2) << "\n";
  if (!out) {
    std::fprintf(stderr, "bench_people: cannot write %s\n", o.json_path.c_str());
    return false;
  }
  return true;
}


}  // namespace inspect::bench_people
