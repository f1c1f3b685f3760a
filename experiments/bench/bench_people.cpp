// bench_people: how well the people detector (shared/perception) finds the
// simulator's people, and what it costs. Seeded scenes in four of the
// repository's worlds: the robot somewhere free, facing anywhere; 0-4 people
// at 1-10 m within the field of view, facing anywhere, standing or walking
// (gait), heights, builds and clothes varied (sim/person_figure.hpp), hidden
// in part by walls, boxes and each other; sensor noise and motion blur on.
// Truth boxes come from the camera model (sim::CameraView::peopleDrawn()).
//
// Per detector and picture size: recall and precision, false boxes per
// picture, bearing error of the box centre, range error from the box's foot
// row on a flat floor, ms per picture; recall by distance, bearing, share
// visible and view (front, side, back). With --video FILE (Debian's
// opencv-doc ships real pedestrians: /usr/share/doc/opencv-doc/examples/
// data/vtest.avi) also detections per frame on real footage (no truth
// there: look at --png's annotated frames). Not a test; ctest runs --quick.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "shared/config/config_node.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/geometry/vec2.hpp"
#include "shared/perception/camera_geometry.hpp"
#include "shared/perception/people_detector.hpp"
#include "shared/util/cli_args.hpp"
#include "shared/util/thread_cpu.hpp"
#include "shared/world/world.hpp"
#include "sim/camera_view.hpp"
#include "tests/support/paths.hpp"
#include "experiments/bench/bench_people_figures.hpp"

namespace {

using namespace inspect;
using namespace inspect::bench_people;
using Clock = std::chrono::steady_clock;
using geometry::Vec2;
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = 180.0 / kPi;

constexpr const char* kUsage =
    "usage: bench_people [--frames N] [--sizes WxH,...] [--detectors NAME,...] [--seed S] [--noise SIGMA]\n"
    "                    [--exposure-ms MS] [--tilt-deg D] [--video FILE] [--video-frames N] [--threads N]\n"
    "                    [--head ptz|wide] [--hfov-deg D] [--z-m M] [--png DIR] [--quick] [--json FILE]\n"
    "Runs the people detector on seeded simulator scenes with truth boxes and reports recall,\n"
    "precision, false boxes per picture, bearing and range error, ms per picture, and recall by\n"
    "distance, bearing, share visible and view. Detectors: hog (OpenCV's default 64x128 people\n"
    "HOG, step 1.05, stride 8), hog-fast (step 1.2), hog-x2 (the picture doubled first; 320x240\n"
    "and smaller only), daimler (48x96 HOG, threshold 0.5), haar-full and haar-upper (opencv-data's\n"
    "cascades); NAME:thr=X:step=Y:up=Z:group=N:floor=1 tries other settings of one (floor=1: the\n"
    "floor band, only windows whose person stands on the floor 1-2.4 m tall).\n"
    "A box counts when its IoU with a truth box is >= 0.3; people less than 30 % visible are\n"
    "neither missed nor found (a box on them is not false). Defaults: 300 pictures per case\n"
    "(--quick: 24, 320x240 only, hog and haar-full), sizes 320x240,640x480, every detector,\n"
    "seed 1, noise 3 grey levels, exposure 8 ms, camera tilt 0 (up positive), --video: opencv-doc's vtest.avi when installed,\n"
    "120 frames of it; OpenCV on 1 thread (--threads). --png DIR writes annotated pictures (truth green, boxes red).\n"
    "--head wide: the second head of config/robot.yaml (wide_camera) with people at 0.6-6 m and recall in\n"
    "bins from 0.6 m and to 62 degrees; --hfov-deg and --z-m change the head's field of view and lens height.\n";

struct DetectorSpec {
  std::string name;
  perception::PeopleDetectorOptions opt;
  int max_width = 4096;  // bigger pictures are left out (too slow to be of use)
};

std::vector<DetectorSpec> catalog() {
  using perception::DetectorMethod;
  std::vector<DetectorSpec> c;
  perception::PeopleDetectorOptions o;
  c.push_back({"hog", o});
  o.scale_step = 1.2;
  c.push_back({"hog-fast", o});
  o = {};
  o.upscale = 2.0;
  c.push_back({"hog-x2", o, 320});
  o = {};
  o.method = DetectorMethod::HogDaimler;
  o.hit_threshold = 0.5;
  c.push_back({"daimler", o});
  o = {};
  o.method = DetectorMethod::HaarFullBody;
  o.scale_step = 1.1;
  o.group_threshold = 3;
  c.push_back({"haar-full", o});
  o.method = DetectorMethod::HaarUpperBody;
  c.push_back({"haar-upper", o});
  return c;
}

struct Frame {
  const sim::World* world;
  sim::CameraScene scene;
};

// A seeded scene: the robot in free space, 0-4 people in front of it (the
// wide head: nearer, 0.6-6 m).
Frame makeScene(const std::vector<sim::World>& worlds, const config::CameraMount& mount, bool wide, std::mt19937_64& rng,
                int k) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const sim::World& w = worlds[static_cast<std::size_t>(k) % worlds.size()];
  Frame f{&w, {}};
  const auto b = world::solidBounds(w);
  const Vec2 lo = b ? b->lo : Vec2{-10, -10}, hi = b ? b->hi : Vec2{10, 10};
  Vec2 at{w.start.x_m, w.start.y_m};
  for (int tries = 0; tries < 200; ++tries) {
    const Vec2 p{lo.x + (hi.x - lo.x) * u(rng), lo.y + (hi.y - lo.y) * u(rng)};
    if (world::clearance(w, p) > 0.6) {
      at = p;
      break;
    }
  }
  // Facing the open: the longest of a few sight lines (a camera against a wall sees no one).
  double theta = 2 * kPi * u(rng), open_m = 0;
  for (int tries = 0; tries < 8; ++tries) {
    const double t = 2 * kPi * u(rng);
    const double d = world::castRay(w, at, t, 12.0).value_or(12.0);
    if (d > open_m) {
      open_m = d;
      theta = t;
    }
  }
  f.scene.robot = {at.x, at.y, theta};
  f.scene.sim_time_s = k / 30.0;
  f.scene.yaw_rate_rad_s = u(rng) < 0.3 ? (u(rng) - 0.5) * 1.2 : 0.0;  // turning on the spot at up to 0.6 rad/s
  const double c = std::cos(f.scene.robot.theta_rad), s = std::sin(f.scene.robot.theta_rad);
  const Vec2 lens{at.x + c * mount.x_m, at.y + s * mount.x_m};
  const int n = static_cast<int>(u(rng) * 5.0);  // 0..4
  const double half_fov = mount.hfov_deg / 2 / kDeg;
  for (int i = 0; i < n; ++i) {
    for (int tries = 0; tries < 40; ++tries) {
      const double d = wide ? 0.6 + 5.4 * u(rng) : 1.0 + 9.0 * u(rng);
      const double bearing = (2 * u(rng) - 1) * (half_fov + 0.05);
      const double yaw = f.scene.robot.theta_rad + bearing;
      const Vec2 p = lens + d * geometry::unitAt(yaw);
      if (world::clearance(w, p) < 0.3) continue;
      // Most stand in the open; some anywhere (behind a wall: not counted).
      const auto hit = world::castRay(w, lens, yaw, d + 0.3);
      if (hit && u(rng) < 0.8) continue;
      sim::PersonInView person;
      person.position = p;
      person.index = k * 8 + i;
      person.heading_rad = 2 * kPi * u(rng);
      person.speed_m_s = u(rng) < 0.6 ? 0.5 + 1.1 * u(rng) : 0.0;
      person.walked_m = 10.0 * u(rng);
      f.scene.people.push_back(person);
      break;
    }
  }
  return f;
}


double iou(const cv::Rect& a, const cv::Rect& b) {
  const double i = (a & b).area();
  const double un = a.area() + b.area() - i;
  return un > 0 ? i / un : 0.0;
}





void drawBoxes(cv::Mat& pic, const std::vector<sim::PersonTruth>* truth, const std::vector<perception::PersonBox>& found) {
  if (truth)
    for (const auto& t : *truth)
      if (!t.box.empty()) cv::rectangle(pic, t.box, t.visible >= 0.3 ? cv::Scalar(0, 220, 0) : cv::Scalar(0, 120, 0), 1);
  for (const auto& d : found) cv::rectangle(pic, d.box, cv::Scalar(0, 0, 255), 2);
}




/// The command line, with --quick's and the footage's defaults applied.
Options parseOptions(int argc, char** argv) {
  Options o;
  bool video_given = false, quick = false, frames_given = false, sizes_given = false;
  cli::readOrExit("bench_people", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--frames")) {
      o.frames = static_cast<int>(a.integer(1, 100000));
      frames_given = true;
    } else if (a.is("--sizes")) {
      o.sizes.clear();
      for (const auto& [w, h] : a.pictureSizes()) o.sizes.emplace_back(w, h);
      sizes_given = true;
    } else if (a.is("--detectors")) {
      o.wanted = a.list();
    } else if (a.is("--seed")) {
      o.seed = a.unsignedInteger(0xFFFFFFFFull);
    } else if (a.is("--noise")) {
      o.noise = a.number(0, 50);
    } else if (a.is("--exposure-ms")) {
      o.exposure_ms = a.number(0, 100);
    } else if (a.is("--tilt-deg")) {
      o.tilt_deg = a.number(-30, 30);
    } else if (a.is("--head")) {
      o.wide = a.choice({"ptz", "wide"}) == "wide";
    } else if (a.is("--hfov-deg")) {
      o.hfov_deg = a.number(10, 150);
    } else if (a.is("--z-m")) {
      o.z_m = a.number(0.05, 5);
    } else if (a.is("--video")) {
      o.video_path = a.text();
      video_given = true;
    } else if (a.is("--video-frames")) {
      o.video_frames = static_cast<int>(a.integer(0, 100000));
    } else if (a.is("--threads")) {
      o.threads = static_cast<int>(a.integer(1, 64));
    } else if (a.is("--png")) {
      o.png_dir = a.path();
    } else if (a.is("--json")) {
      o.json_path = a.path();
    } else if (a.is("--quick")) {
      quick = true;
    } else {
      a.unknown();
    }
  });
  if (quick) {
    if (!frames_given) o.frames = 24;
    if (!sizes_given) o.sizes = {{320, 240}};
    if (o.wanted.empty()) o.wanted = {"hog", "haar-full"};
    if (!video_given) o.video_frames = 0;
  }
  const std::string kVtest = "/usr/share/doc/opencv-doc/examples/data/vtest.avi";
  if (!video_given && std::filesystem::exists(kVtest)) o.video_path = kVtest;
  return o;
}

/// The detectors asked for: NAME or NAME:key=value:... (thr, step, up, group)
/// to try other settings of one; every one when none is named. nullopt
/// (printed why) on a name or setting that is not known.
std::optional<std::vector<DetectorSpec>> detectorSpecs(const std::vector<std::string>& wanted) {
  std::vector<DetectorSpec> specs;
  if (wanted.empty()) specs = catalog();
  for (const auto& w : wanted) {
    const std::string base = w.substr(0, w.find(':'));
    const auto cat = catalog();
    const auto it = std::find_if(cat.begin(), cat.end(), [&](const DetectorSpec& d) { return d.name == base; });
    if (it == cat.end()) {
      std::fprintf(stderr, "bench_people: --detectors: '%s' is not one of hog, hog-fast, hog-x2, daimler, haar-full, haar-upper\n",
                   base.c_str());
      return std::nullopt;
    }
    DetectorSpec d = *it;
    d.name = w;
    for (std::size_t at = w.find(':'); at != std::string::npos;) {
      const std::size_t next = w.find(':', at + 1);
      const std::string kv = w.substr(at + 1, next == std::string::npos ? std::string::npos : next - at - 1);
      const std::size_t eq = kv.find('=');
      char* end = nullptr;
      const double v = eq == std::string::npos ? NAN : std::strtod(kv.c_str() + eq + 1, &end);
      const std::string key = kv.substr(0, eq);
      if (!std::isfinite(v) || (end && *end) ||
          (key != "thr" && key != "step" && key != "up" && key != "group" && key != "floor")) {
        std::fprintf(stderr, "bench_people: --detectors: '%s' in '%s' is not thr=, step=, up=, group= or floor= with a number\n",
                     kv.c_str(), w.c_str());
        return std::nullopt;
      }
      if (key == "thr") d.opt.hit_threshold = v;
      if (key == "step") d.opt.scale_step = v;
      if (key == "up") d.opt.upscale = v;
      if (key == "group") d.opt.group_threshold = static_cast<int>(v);
      if (key == "floor") d.opt.floor_band = v != 0;
      at = next;
    }
    specs.push_back(d);
  }
  return specs;
}

/// One picture's boxes against its truth: greedy matching, strongest box
/// first (IoU >= 0.3; upper-body boxes against the figure's top 35 %), the
/// bearing and range errors of the matches, and the recall bins.
void scoreFrame(Case& c, const std::vector<perception::PersonBox>& found, const std::vector<sim::PersonTruth>& truth,
                const Frame& fr, const perception::CameraPose& cam) {
  std::vector<std::size_t> order(found.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return found[a].score > found[b].score; });
  std::vector<bool> taken(truth.size(), false);
  for (const std::size_t i : order) {
    const auto& d = found[i];
    ++c.boxes;
    double best = 0.3;
    int who = -1;
    for (std::size_t t = 0; t < truth.size(); ++t) {
      if (taken[t] || truth[t].box.empty()) continue;
      cv::Rect ref = truth[t].box;
      if (d.upper_body) ref.height = std::max(1, static_cast<int>(std::lround(0.35 * truth[t].full_box.height)));
      const double o = iou(d.box, ref);
      if (o >= best) {
        best = o;
        who = static_cast<int>(t);
      }
    }
    if (who < 0) {
      ++c.false_boxes;
      continue;
    }
    taken[static_cast<std::size_t>(who)] = true;
    const auto& t = truth[static_cast<std::size_t>(who)];
    if (t.visible < 0.3) continue;  // neither found nor false
    // What the robot computes (shared/perception/camera_geometry), against the camera model's truth.
    const perception::Sighting seen = perception::sightingOf(d.box, cam);
    c.bearing_err_deg.push_back(std::abs(std::remainder(seen.bearing_rad - t.bearing_rad, 2 * kPi)) * kDeg);
    if (!d.upper_body && t.feet_in_view && seen.range_m) {
      c.range_err_pct.push_back(100.0 * std::abs(*seen.range_m - t.distance_m) / t.distance_m);
      c.range_signed_pct.push_back(100.0 * (*seen.range_m - t.distance_m) / t.distance_m);
    }
  }
  for (std::size_t t = 0; t < truth.size(); ++t) {
    const auto& p = truth[t];
    if (p.visible < 0.3 || p.box.empty()) continue;
    ++c.truths;
    if (taken[t]) ++c.found;
    const bool hit = taken[t];
    c.by_distance.add(p.distance_m, hit);
    c.by_bearing.add(std::abs(p.bearing_rad) * kDeg, hit);
    c.by_visible.add(p.visible, hit);
    c.by_view.add(std::abs(p.view_rad) * kDeg, hit);
    double speed = 0;
    for (const auto& q : fr.scene.people)
      if (q.index == p.index) speed = q.speed_m_s;
    c.by_motion.add(speed, hit);
    (p.visible >= 0.9 ? c.by_distance_clear : c.by_distance_part).add(p.distance_m, hit);
  }
}

/// The simulated pictures: every detector at every size it takes, scored
/// against the camera model's truth. Annotated pictures of the first
/// detector go to --png.
std::vector<Case> runSynthetic(const Options& o, const std::vector<DetectorSpec>& specs,
                               const std::vector<sim::World>& worlds, const config::CameraMount& mount,
                               const std::vector<Frame>& scenes, std::vector<std::string>& pngs) {
  sim::CameraViewStyle style;
  style.look_seed = static_cast<uint32_t>(o.seed);
  style.noise_sigma = o.noise;
  style.exposure_ms = o.exposure_ms;
  std::vector<Case> cases;
  for (const auto& sz : o.sizes) {
    // One view per world at this size.
    std::vector<sim::CameraView> views;
    for (const auto& w : worlds) views.emplace_back(w, mount, sz.width, sz.height, style);
    for (const auto& spec : specs) {
      if (sz.width > spec.max_width) continue;
      std::optional<perception::PeopleDetector> det;
      try {
        det.emplace(spec.opt);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_people: %s left out: %s\n", spec.name.c_str(), e.what());
        continue;
      }
      std::fprintf(stderr, "bench_people: %s at %dx%d ...\n", spec.name.c_str(), sz.width, sz.height);
      Case c;
      c.detector = spec.name;
      c.settings = perception::describe(spec.opt);
      c.width = sz.width;
      c.height = sz.height;
      if (o.wide) c.useWideBins();
      for (auto* b : c.all()) b->init();
      cv::Mat pic;
      double cpu = 0;
      for (int k = 0; k < o.frames; ++k) {
        const Frame& fr = scenes[static_cast<std::size_t>(k)];
        auto& view = views[static_cast<std::size_t>(k) % worlds.size()];
        view.render(fr.scene, 1000000ull + 33333ull * static_cast<uint64_t>(k), static_cast<uint32_t>(k), pic);
        const auto& truth = view.peopleDrawn();
        perception::CameraPose cam;
        cam.width = sz.width;
        cam.height = sz.height;
        cam.mount = mount;
        cam.tilt_rad = fr.scene.tilt_rad;
        const auto t0 = Clock::now();
        const double cpu0 = util::threadCpuMs();
        const auto found = det->detect(pic, &cam);
        cpu += util::threadCpuMs() - cpu0;
        c.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        ++c.frames;
        scoreFrame(c, found, truth, fr, cam);
        if (!o.png_dir.empty() && (k % std::max(1, o.frames / 4)) == 0 && &spec == &specs.front()) {
          cv::Mat shown = pic.clone();
          drawBoxes(shown, &truth, found);
          const std::string file = o.png_dir + "/people_" + (o.wide ? "wide_" : "") + std::to_string(sz.width) + "x" +
                                   std::to_string(sz.height) + "_" + spec.name + "_" + std::to_string(k) + ".png";
          if (cv::imwrite(file, shown)) pngs.push_back(file);
        }
      }
      c.cpu_ms = cpu / std::max(1, c.frames);
      cases.push_back(std::move(c));
    }
  }
  return cases;
}

/// Real footage (no truth): boxes per frame at full and half size. nullopt
/// (printed why) when no frame of the file can be read.
std::optional<std::vector<VideoCase>> runFootage(const Options& o, const std::vector<DetectorSpec>& specs,
                                                 std::vector<std::string>& pngs) {
  std::vector<VideoCase> vcases;
  if (o.video_path.empty() || o.video_frames <= 0) return vcases;
  cv::VideoCapture cap(o.video_path);
  std::vector<cv::Mat> clip;
  cv::Mat m;
  while (static_cast<int>(clip.size()) < o.video_frames && cap.read(m)) clip.push_back(m.clone());
  if (clip.empty()) {
    std::fprintf(stderr, "bench_people: --video %s: no frame could be read\n", o.video_path.c_str());
    return std::nullopt;
  }
  for (const double scale : {1.0, 0.5}) {
    for (const auto& spec : specs) {
      if (spec.name == "hog-x2" && scale == 1.0) continue;
      std::optional<perception::PeopleDetector> det;
      try {
        det.emplace(spec.opt);
      } catch (const std::exception&) {
        continue;
      }
      VideoCase v;
      v.detector = spec.name;
      int with_box = 0;
      uint64_t boxes = 0;
      for (std::size_t i = 0; i < clip.size(); ++i) {
        cv::Mat in;
        if (scale != 1.0)
          cv::resize(clip[i], in, cv::Size(), scale, scale, cv::INTER_AREA);
        else
          in = clip[i];
        v.width = in.cols;
        v.height = in.rows;
        const auto t0 = Clock::now();
        const auto found = det->detect(in);
        v.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        boxes += found.size();
        if (!found.empty()) ++with_box;
        if (!o.png_dir.empty() && (i == 0 || i == clip.size() / 2)) {
          cv::Mat shown = in.clone();
          drawBoxes(shown, nullptr, found);
          const std::string file = o.png_dir + "/vtest_" + std::to_string(in.cols) + "_" + spec.name + "_" +
                                   std::to_string(i) + ".png";
          if (cv::imwrite(file, shown)) pngs.push_back(file);
        }
      }
      v.frames = static_cast<int>(clip.size());
      v.boxes_per_frame = static_cast<double>(boxes) / v.frames;
      v.frames_with_box_pct = 100.0 * with_box / v.frames;
      vcases.push_back(std::move(v));
    }
  }
  return vcases;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parseOptions(argc, argv);
  // One thread, as the robot gives it (OpenCV's HOG and cascades otherwise spread over every core).
  cv::setNumThreads(o.threads);
  const auto specs = detectorSpecs(o.wanted);
  if (!specs) return 2;

  std::vector<sim::World> worlds;
  config::RobotConfig robot;
  try {
    for (const char* name : {"warehouse", "narrow_aisle", "gas_lab", "square_room"})
      worlds.push_back(sim::loadWorldFile(test::srcPath(std::string("config/worlds/") + name + ".yaml")));
    robot = config::loadRobotConfigFile(test::srcPath("config/robot.yaml"));
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "bench_people: %s\n", e.what());
    return 2;
  }
  if (o.wide && !robot.wide_camera) {
    std::fprintf(stderr, "bench_people: --head wide: config/robot.yaml has no wide_camera section\n");
    return 2;
  }
  config::CameraMount mount = o.wide ? *robot.wide_camera : robot.camera;
  if (o.hfov_deg > 0) mount.hfov_deg = o.hfov_deg;
  if (o.z_m > 0) mount.z_m = o.z_m;
  std::mt19937_64 rng(o.seed);
  std::vector<Frame> scenes;
  for (int k = 0; k < o.frames; ++k) {
    scenes.push_back(makeScene(worlds, mount, o.wide, rng, k));
    scenes.back().scene.tilt_rad = o.tilt_deg / kDeg;
  }
  if (!o.png_dir.empty()) std::filesystem::create_directories(o.png_dir);

  std::vector<std::string> pngs;
  std::vector<Case> cases = runSynthetic(o, *specs, worlds, mount, scenes, pngs);
  const auto vcases = runFootage(o, *specs, pngs);
  if (!vcases) return 1;
  printTables(o, mount, cases, *vcases, pngs);
  if (!o.json_path.empty() && !writeJson(o, mount, cases, *vcases)) return 1;
  return 0;
}
