// bench_camera: cost of mcu_sim's simulated camera (sim/camera_view.hpp) per
// picture, against the synthetic source's drawing (shared/video/frame_source.hpp)
// of the same size in the same run, and the frame slot's hand-off
// (shared/video/frame_slot.hpp: one write and one read of a picture). The
// robot turns once round on the world's start pose while the camera pans
// +-45 degrees, with the pedestrians at the first points of their routes, so
// that every wall is seen. Per case: wall time per picture (median, p99,
// max) and the thread's CPU time per picture. The target: the camera view at
// 640x480 within 5 ms of CPU per picture. Not a test; the ctest smoke entry
// runs --quick.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "shared/config/config_node.hpp"
#include "shared/config/robot_config.hpp"
#include "shared/util/cli_args.hpp"
#include "shared/util/thread_cpu.hpp"
#include "shared/video/frame_slot.hpp"
#include "shared/video/frame_source.hpp"
#include "sim/camera_view.hpp"
#include "tests/support/paths.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using namespace inspect;

constexpr const char* kUsage =
    "usage: bench_camera [--frames N] [--sizes WxH,...] [--world FILE] [--robot FILE] [--png DIR]\n"
    "                    [--quick] [--json FILE]\n"
    "Times mcu_sim's camera view per picture (wall time median/p99/max, CPU time of the thread)\n"
    "against the synthetic video source drawing the same size in the same run, and the frame\n"
    "slot's hand-off (write + read of one picture). The robot turns once round on the world's\n"
    "start pose while the camera pans +-45 deg; pedestrians stand at their routes' first points.\n"
    "Defaults: 600 pictures per case (--quick: 60), sizes 640x480,320x240, the repository's\n"
    "config/worlds/gas_lab.yaml and config/robot.yaml (its camera mount). --png DIR also writes\n"
    "four of the camera's pictures per size; --json FILE writes the figures.\n";

struct Case {
  std::string name;
  int width = 0, height = 0;
  int frames = 0;
  double p50_ms = 0, p99_ms = 0, max_ms = 0;  // wall time per picture
  double cpu_ms = 0;                          // thread CPU time per picture (mean)
};


// Warm-up (10 calls), then `frames` timed calls of body(k).
Case timeFrames(const std::string& name, int w, int h, int frames, const std::function<void(int)>& body) {
  for (int k = 0; k < 10; ++k) body(k);
  std::vector<double> ms;
  ms.reserve(static_cast<std::size_t>(frames));
  const double cpu0 = util::threadCpuMs();
  for (int k = 0; k < frames; ++k) {
    const auto t0 = Clock::now();
    body(k);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  const double cpu = util::threadCpuMs() - cpu0;
  std::sort(ms.begin(), ms.end());
  auto at = [&](double q) { return ms[std::min(ms.size() - 1, static_cast<std::size_t>(q * (ms.size() - 1) + 0.5))]; };
  return {name, w, h, frames, at(0.5), at(0.99), ms.back(), cpu / frames};
}

// The scene of picture k of n: one turn of the robot, the camera panning.
sim::CameraScene sceneAt(const sim::World& world, int k, int n) {
  constexpr double kPi = 3.14159265358979323846;
  sim::CameraScene s;
  s.robot = world.start;
  s.robot.theta_rad = world.start.theta_rad + 2 * kPi * k / n;
  s.pan_rad = (kPi / 4) * std::sin(6 * kPi * k / n);
  s.tilt_rad = -0.1 * std::sin(2 * kPi * k / n);
  s.sim_time_s = k / 30.0;
  s.yaw_rate_rad_s = 2 * kPi / (n / 30.0);  // one turn over the run at 30 fps
  for (std::size_t i = 0; i < world.pedestrians.size(); ++i) {
    const auto& r = world.pedestrians[i].route;
    // Walking on the spot at 1 m/s, turning: every view and gait phase is drawn.
    if (!r.empty())
      s.people.push_back({r.front(), world.pedestrians[i].radius_m, static_cast<int>(i), 4 * kPi * k / n, 1.0,
                          0.033 * k});
  }
  return s;
}

/// Every case at every size: the camera view plain and with noise and blur,
/// the synthetic source, the frame slot's hand-off; --png's pictures.
std::vector<Case> runCases(const sim::World& world, const config::RobotConfig& robot, const std::vector<cv::Size>& sizes,
                           int frames, const std::vector<sim::CameraScene>& scenes, const std::string& png_dir,
                           std::vector<std::string>& pngs) {
  const std::string slot_path = "/dev/shm/bench_camera-" + std::to_string(::getpid()) + ".slot";
  std::vector<Case> cases;
  for (const auto& sz : sizes) {
    const std::string tag = std::to_string(sz.width) + "x" + std::to_string(sz.height);
    sim::CameraView view(world, robot.camera, sz.width, sz.height);
    cv::Mat frame;
    cases.push_back(timeFrames("camera view " + tag, sz.width, sz.height, frames, [&](int k) {
      view.render(scenes[static_cast<std::size_t>(k % frames)], 1000000ull + 33333ull * k, static_cast<uint32_t>(k),
                  frame);
    }));
    // As bench_people draws it: sensor noise (3 grey levels) and motion blur (8 ms exposure).
    sim::CameraViewStyle real;
    real.noise_sigma = 3.0;
    real.exposure_ms = 8.0;
    sim::CameraView real_view(world, robot.camera, sz.width, sz.height, real);
    cv::Mat real_frame;
    cases.push_back(timeFrames("camera view, noise + blur " + tag, sz.width, sz.height, frames, [&](int k) {
      real_view.render(scenes[static_cast<std::size_t>(k % frames)], 1000000ull + 33333ull * k,
                       static_cast<uint32_t>(k), real_frame);
    }));
    video::SyntheticSource synthetic(sz.width, sz.height);
    cv::Mat syn;
    cases.push_back(timeFrames("synthetic source " + tag, sz.width, sz.height, frames, [&](int k) {
      synthetic.read(syn, 1000000ull + 33333ull * k, static_cast<uint32_t>(k));
    }));
    try {
      video::FrameSlotWriter writer(slot_path, sz.width, sz.height, 30.0);
      video::FrameSlotReader reader(slot_path);
      cv::Mat back(sz.height, sz.width, CV_8UC3);
      uint64_t seq = 0;
      cases.push_back(timeFrames("frame slot write + read " + tag, sz.width, sz.height, frames, [&](int k) {
        writer.write(frame.data, frame.step, 1000000ull + 33333ull * k, static_cast<uint32_t>(k));
        if (const auto f = reader.readNewer(seq, back.data, back.step, std::chrono::milliseconds(100))) seq = f->seq;
      }));
    } catch (const video::VideoError& e) {
      std::fprintf(stderr, "bench_camera: frame slot: %s (case left out)\n", e.what());
    }
    if (!png_dir.empty()) {
      for (int q = 0; q < 4; ++q) {
        const int k = q * frames / 4;
        view.render(scenes[static_cast<std::size_t>(k)], 1000000ull + 33333ull * k, static_cast<uint32_t>(k), frame);
        const std::string file = png_dir + "/camera_" + tag + "_" + std::to_string(q) + ".png";
        if (cv::imwrite(file, frame)) pngs.push_back(file);
      }
    }
  }

  return cases;
}

}  // namespace

int main(int argc, char** argv) {
  std::string world_path = inspect::test::srcPath("config/worlds/gas_lab.yaml");
  std::string robot_path = inspect::test::srcPath("config/robot.yaml");
  std::string json_path, png_dir;
  std::vector<cv::Size> sizes{{640, 480}, {320, 240}};
  int frames = 600;
  bool quick = false, frames_given = false;
  cli::readOrExit("bench_camera", argc, argv, [&](cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--frames")) {
      frames = static_cast<int>(a.integer(10, 1000000));
      frames_given = true;
    } else if (a.is("--sizes")) {
      sizes.clear();
      for (const auto& [w, h] : a.pictureSizes()) sizes.emplace_back(w, h);
    } else if (a.is("--world")) {
      world_path = a.path();
    } else if (a.is("--robot")) {
      robot_path = a.path();
    } else if (a.is("--png")) {
      png_dir = a.path();
    } else if (a.is("--json")) {
      json_path = a.path();
    } else if (a.is("--quick")) {
      quick = true;
    } else {
      a.unknown();
    }
  });
  if (quick && !frames_given) frames = 60;

  sim::World world;
  config::RobotConfig robot;
  try {
    world = sim::loadWorldFile(world_path);
    robot = config::loadRobotConfigFile(robot_path);
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "bench_camera: %s\n", e.what());
    return 2;
  }
  std::vector<sim::CameraScene> scenes;
  for (int k = 0; k < frames; ++k) scenes.push_back(sceneAt(world, k, frames));
  if (!png_dir.empty()) std::filesystem::create_directories(png_dir);

  std::vector<std::string> pngs;
  const std::vector<Case> cases = runCases(world, robot, sizes, frames, scenes, png_dir, pngs);

  // Table.
  std::size_t obstacle_edges = 0;
  for (const auto& o : world.obstacles) obstacle_edges += o.polygon.vertices.size();
  std::printf("bench_camera: %s (%zu wall segments, %zu obstacles with %zu edges, %zu floor lines, %zu people), "
              "%d pictures per case, one thread\n\n",
              world_path.c_str(), world.walls.size(), world.obstacles.size(), obstacle_edges,
              world.floor_lines.size(), world.pedestrians.size(), frames);
  std::printf("%-40s %10s %10s %10s %14s %14s\n", "case", "p50 ms", "p99 ms", "max ms", "CPU ms/frame",
              "vs synthetic");
  auto synthetic_of = [&](const Case& c) {
    for (const auto& s : cases)
      if (s.name.rfind("synthetic", 0) == 0 && s.width == c.width && s.height == c.height) return s.cpu_ms;
    return std::nan("");
  };
  for (const auto& c : cases)
    std::printf("%-40s %10.3f %10.3f %10.3f %14.3f %13.2fx\n", c.name.c_str(), c.p50_ms, c.p99_ms, c.max_ms, c.cpu_ms,
                c.cpu_ms / synthetic_of(c));
  std::printf("'vs synthetic' = this case's CPU time / the synthetic source's at the same size.\n");
  const Case* vga = nullptr;
  for (const auto& c : cases)
    if (c.name.rfind("camera view", 0) == 0 && c.width == 640 && c.height == 480) vga = &c;
  if (vga)
    std::printf("target: camera view <= 5 ms CPU per 640x480 picture: %s (%.3f ms, p99 wall %.3f ms)\n",
                vga->cpu_ms <= 5.0 ? "met" : "NOT met", vga->cpu_ms, vga->p99_ms);
  for (const auto& p : pngs) std::printf("picture: %s\n", p.c_str());

  if (!json_path.empty()) {
    nlohmann::ordered_json j;
    j["world"] = world_path;
    j["pictures_per_case"] = frames;
    j["wall_segments"] = world.walls.size();
    j["obstacle_edges"] = obstacle_edges;
    j["floor_lines"] = world.floor_lines.size();
    j["people"] = world.pedestrians.size();
    auto& jc = j["cases"];
    jc = nlohmann::ordered_json::array();
    for (const auto& c : cases) {
      const double ratio = c.cpu_ms / synthetic_of(c);
      jc.push_back({{"case", c.name},
                    {"width", c.width},
                    {"height", c.height},
                    {"wall_ms_p50", c.p50_ms},
                    {"wall_ms_p99", c.p99_ms},
                    {"wall_ms_max", c.max_ms},
                    {"cpu_ms_per_frame", c.cpu_ms},
                    {"cpu_vs_synthetic", std::isfinite(ratio) ? nlohmann::ordered_json(ratio) : nullptr}});
    }
    j["target_cpu_ms_640x480"] = 5.0;
    j["target_met"] = vga ? nlohmann::ordered_json(vga->cpu_ms <= 5.0) : nlohmann::ordered_json(nullptr);
    std::ofstream f(json_path);
    f << j.dump(2) << "\n";
    if (!f) {
      std::fprintf(stderr, "bench_camera: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
}
