// bench_fuzzy: time per evaluation of a controller (default: the shipped
// fuzzy_pid.fis) through our Engine, our LookupSurface and, when built with
// it, the fuzzylite C++ library, in the same run. Not a test.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <cstdint>
#include <span>
#include <memory>
#include <string>
#include <vector>

#include "shared/util/cli_args.hpp"
#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/lookup_surface.hpp"

#ifdef INSPECT_HAVE_FUZZYLITE
#include <fl/Headers.h>
#include "tests/support/paths.hpp"
#endif

namespace {

using Clock = std::chrono::steady_clock;
namespace fz = inspect::fuzzy;

constexpr const char* kUsage =
    "usage: bench_fuzzy [--fis FILE.fis] [--reps N] [--json FILE] [--quick]\n"
    "Times one evaluation of FILE.fis (default config/fuzzy/fuzzy_pid.fis) by the\n"
    "engine (direct), the lookup surface and the fuzzylite library, and prints a\n"
    "table with ratios; --json also writes the figures to FILE.\n";

struct Result {
  std::string name;
  double median_ns = 0;
  double min_ns = 0;
  long calls_per_rep = 0;
};

// Runs `body(i)` for i over the input set; warm-up, then `reps` timed passes
// of `calls` calls each. Returns median and minimum ns per call.
Result timeIt(const std::string& name, long calls, int reps, const std::function<double(std::size_t)>& body,
              std::size_t n_inputs) {
  volatile double sink = 0;
  double acc = 0;
  for (long i = 0; i < std::min<long>(calls / 10 + 1, 20000); ++i) acc += body(static_cast<std::size_t>(i) % n_inputs);
  std::vector<double> per_call;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    for (long i = 0; i < calls; ++i) acc += body(static_cast<std::size_t>(i) % n_inputs);
    const auto t1 = Clock::now();
    per_call.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / static_cast<double>(calls));
  }
  sink = acc;
  (void)sink;
  std::sort(per_call.begin(), per_call.end());
  return Result{name, per_call[per_call.size() / 2], per_call.front(), calls};
}

/// What the table and the JSON report besides the timings.
struct Figures {
  std::string fis_path;
  std::size_t inputs = 0, outputs = 0, rules = 0;
  int reps = 0;
  double engine_ns = 0, fl_ns = 0;  // the engine's and fuzzylite's median ns per call (NaN: not built in)
  std::size_t lookup_points = 0;
  double surface_error = 0, max_diff_fl = 0;
};

void printTable(const Figures& f, const std::vector<Result>& results) {
  const auto& fis_path = f.fis_path;
  const std::size_t n_in = f.inputs, n_out = f.outputs;
  const int reps = f.reps;
  const double engine_ns = f.engine_ns, fl_ns = f.fl_ns, surface_error = f.surface_error, max_diff_fl = f.max_diff_fl;
  std::printf("bench_fuzzy: %s (%zu inputs, %zu outputs, %zu rules), %d repetitions, median of per-call times\n\n",
              fis_path.c_str(), n_in, n_out, f.rules, reps);
  std::printf("%-36s %12s %12s %12s %14s\n", "method", "ns/call", "min ns/call", "vs engine", "vs fuzzylite");
  for (const auto& r : results) {
    std::printf("%-36s %12.1f %12.1f %11.2fx", r.name.c_str(), r.median_ns, r.min_ns, engine_ns / r.median_ns);
    if (std::isfinite(fl_ns)) {
      std::printf(" %13.2fx\n", fl_ns / r.median_ns);
    } else {
      std::printf(" %14s\n", "-");
    }
  }
  std::printf("\n'vs X' = how many times faster than X (X's time / this time).\n");
  std::printf("lookup surface max |interpolation error| vs direct: %.4g\n", surface_error);
  if (std::isfinite(max_diff_fl)) {
    std::printf("max |engine - fuzzylite| on the bench inputs: %.4g (sampling: 101 points vs 100 midpoints)\n", max_diff_fl);
  } else {
    std::printf("fuzzylite: not built in (install libfuzzylite-dev and re-run cmake)\n");
  }
}

/// The figures as JSON (--json); false (printed why) when the file cannot be written.
bool writeJson(const std::string& json_path, const Figures& f, const std::vector<Result>& results) {
  const auto& fis_path = f.fis_path;
  const int reps = f.reps;
  const double engine_ns = f.engine_ns, fl_ns = f.fl_ns, surface_error = f.surface_error, max_diff_fl = f.max_diff_fl;
  std::ofstream js(json_path);
  if (!js) {
    std::fprintf(stderr, "bench_fuzzy: cannot write %s\n", json_path.c_str());
    return false;
  }
  auto num = [](double v) {
    if (!std::isfinite(v)) return std::string("null");
    char b[64];
    std::snprintf(b, sizeof b, "%.6g", v);
    return std::string(b);
  };
  js << "{\n  \"fis\": \"" << fis_path << "\",\n  \"repetitions\": " << reps << ",\n  \"results\": [\n";
  for (std::size_t i = 0; i < results.size(); ++i) {
    const auto& r = results[i];
    js << "    {\"method\": \"" << r.name << "\", \"ns_per_call_median\": " << num(r.median_ns)
       << ", \"ns_per_call_min\": " << num(r.min_ns) << ", \"calls_per_repetition\": " << r.calls_per_rep
       << ", \"speedup_vs_engine\": " << num(engine_ns / r.median_ns)
       << ", \"speedup_vs_fuzzylite\": " << num(fl_ns / r.median_ns) << "}" << (i + 1 < results.size() ? "," : "")
       << "\n";
  }
  js << "  ],\n  \"lookup_points_per_input\": " << f.lookup_points
     << ",\n  \"lookup_max_interpolation_error\": " << num(surface_error)
     << ",\n  \"max_abs_diff_engine_vs_fuzzylite\": " << num(max_diff_fl) << "\n}\n";
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string fis_path = inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis");
  std::string json_path;
  int reps = 7;
  bool quick = false;
  inspect::cli::readOrExit("bench_fuzzy", argc, argv, [&](inspect::cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--fis")) {
      fis_path = a.path();
    } else if (a.is("--json")) {
      json_path = a.path();
    } else if (a.is("--reps")) {
      reps = static_cast<int>(a.integer(1, 1000000));
    } else if (a.is("--quick")) {
      quick = true;
    } else {
      a.unknown();
    }
  });

  std::unique_ptr<fz::Engine> engine;
  std::unique_ptr<fz::LookupSurface> surface;
  fz::Fis fis;
  try {
    fis = fz::readFisFile(fis_path);
    engine = std::make_unique<fz::Engine>(fis);
    surface = std::make_unique<fz::LookupSurface>(fis);
  } catch (const fz::FisError& e) {
    std::fprintf(stderr, "bench_fuzzy: %s\n", e.what());
    return 2;
  }
  const std::size_t n_in = engine->numInputs();
  const std::size_t n_out = engine->numOutputs();

  // Fixed pseudo-random inputs over the input ranges (same for every method).
  constexpr std::size_t kInputs = 4096;
  std::vector<double> inputs(kInputs * n_in);
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  for (std::size_t k = 0; k < kInputs; ++k) {
    for (std::size_t i = 0; i < n_in; ++i) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      const double u = static_cast<double>(state >> 11) / 9007199254740992.0;
      inputs[k * n_in + i] = fis.inputs[i].min + u * (fis.inputs[i].max - fis.inputs[i].min);
    }
  }
  std::vector<double> out(n_out);
  auto in = [&](std::size_t k) { return std::span<const double>(inputs.data() + k * n_in, n_in); };

  const long scale = quick ? 10 : 1;
  std::vector<Result> results;
  results.push_back(timeIt("engine (direct, 101 samples)", 40000 / scale, reps, [&](std::size_t k) {
    engine->evaluate(in(k), out);
    return out[0];
  }, kInputs));
  char surface_name[96];
  std::snprintf(surface_name, sizeof surface_name, "lookup surface (%zu points/input)", surface->pointsPerInput());
  results.push_back(timeIt(surface_name, 4000000 / scale, reps, [&](std::size_t k) {
    surface->evaluate(in(k), out);
    return out[0];
  }, kInputs));

  double max_diff_fl = std::nan("");
#ifdef INSPECT_HAVE_FUZZYLITE
  std::unique_ptr<fl::Engine> fle;
  try {
    fl::FisImporter importer;
    fle.reset(importer.fromFile(fis_path));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_fuzzy: fuzzylite cannot import %s: %s\n", fis_path.c_str(), e.what());
    return 2;
  }
  std::string status;
  if (!fle->isReady(&status)) {
    std::fprintf(stderr, "bench_fuzzy: fuzzylite engine not ready: %s\n", status.c_str());
    return 2;
  }
  auto flEval = [&](std::size_t k) {
    for (std::size_t i = 0; i < n_in; ++i) fle->getInputVariable(i)->setValue(inputs[k * n_in + i]);
    fle->process();
    return fle->getOutputVariable(0)->getValue();
  };
  results.push_back(timeIt("fuzzylite 6 (resolution 100)", 4000 / scale, reps, flEval, kInputs));
  max_diff_fl = 0;
  for (std::size_t k = 0; k < kInputs; k += 7) {
    flEval(k);
    engine->evaluate(in(k), out);
    for (std::size_t o = 0; o < n_out; ++o) {
      const double v = fle->getOutputVariable(o)->getValue();
      if (std::isfinite(v)) max_diff_fl = std::max(max_diff_fl, std::abs(v - out[o]));
    }
  }
#endif
  const double surface_error = surface->maxInterpolationError();

  const double engine_ns = results[0].median_ns;
  const double fl_ns = results.size() > 2 ? results[2].median_ns : std::nan("");
  const Figures figures{fis_path, n_in, n_out, fis.rules.size(), reps, engine_ns, fl_ns, surface->pointsPerInput(),
                        surface_error, max_diff_fl};
  printTable(figures, results);

  if (!json_path.empty() && !writeJson(json_path, figures, results)) return 2;
  return 0;
}
