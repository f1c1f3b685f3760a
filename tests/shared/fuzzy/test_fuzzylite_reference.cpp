// The reference comparison: the Debian `fuzzylite` command-line tool
// evaluates the same .fis files on the same input grids, and our engine must
// agree within what the different output sampling explains (docs/fuzzy.md).
// Without fuzzylite these tests FAIL: scripts/setup.sh installs it.
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "tests/support/paths.hpp"

namespace inspect::fuzzy {
namespace {

namespace fs = std::filesystem;
using Rows = std::vector<std::vector<double>>;

constexpr const char* kMissing =
    "the fuzzylite command-line tool is not installed (Debian package 'fuzzylite'; scripts/setup.sh installs it). "
    "The reference comparison cannot run without it.";

// fuzzylite's integral defuzzifiers sample at `resolution` midpoints
// min + (i + 0.5) dx; ours (MATLAB) at `samples` points min + k step with
// both ends. Matched mode raises both so that both approximate the same
// integral closely; default mode compares MATLAB's 101 against fuzzylite's 100.
constexpr int kMatchedResolution = 2000;
constexpr std::size_t kMatchedSamples = 2001;
// fuzzylite treats |a - b| < 1e-6 as equal (fl::fuzzylite::macheps): a rule
// firing below it is not triggered.
constexpr double kFuzzyliteMacheps = 1e-6;

bool haveFuzzylite() { return std::system("command -v fuzzylite >/dev/null 2>&1") == 0; }

struct RefCase {
  const char* file;    // path below the source tree
  bool offset_only;    // mom: grids that avoid exact ties between rules
};

void PrintTo(const RefCase& c, std::ostream* os) { *os << c.file; }

std::string readAll(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Rows parseRows(const std::string& text) {
  Rows rows;
  std::istringstream is(text);
  std::string line;
  while (std::getline(is, line)) {
    std::vector<double> row;
    std::istringstream ls(line);
    std::string tok;
    while (ls >> tok) {
      double v = 0;
      auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
      if (ec != std::errc() || p != tok.data() + tok.size()) {
        ADD_FAILURE() << "fuzzylite printed '" << tok << "'";
        v = std::nan("");
      }
      row.push_back(v);
    }
    if (!row.empty()) rows.push_back(std::move(row));
  }
  return rows;
}

// Inputs: a 25 x 25 grid from 10 % below to 10 % above each range (it hits
// both range ends and some MF breakpoints) and a 19 x 19 grid shifted by an
// irrational fraction of a cell inside the ranges (no exact ties).
Rows inputGrid(const Fis& fis, bool offset_only) {
  std::vector<std::vector<double>> axes_reg, axes_off;
  for (const auto& v : fis.inputs) {
    const double r = v.max - v.min;
    std::vector<double> reg, off;
    for (int i = 0; i < 25; ++i) reg.push_back(v.min - 0.1 * r + 1.2 * r * i / 24.0);
    for (int i = 0; i < 19; ++i) off.push_back(v.min + r * (i + 0.381966011250105) / 19.0);
    axes_reg.push_back(reg);
    axes_off.push_back(off);
  }
  Rows rows;
  auto cross = [&](const std::vector<std::vector<double>>& axes) {
    std::vector<std::size_t> idx(axes.size(), 0);
    while (true) {
      std::vector<double> row;
      for (std::size_t d = 0; d < axes.size(); ++d) row.push_back(axes[d][idx[d]]);
      rows.push_back(row);
      std::size_t d = 0;
      while (d < axes.size() && ++idx[d] == axes[d].size()) idx[d++] = 0;
      if (d == axes.size()) break;
    }
  };
  if (!offset_only) cross(axes_reg);
  cross(axes_off);
  return rows;
}

class TempDir {
 public:
  explicit TempDir(const std::string& tag)
      : path_(fs::temp_directory_path() / ("inspect_fuzzy_ref_" + std::to_string(::getpid()) + "_" + tag)) {
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

bool run(const std::string& cmd, std::string& log) {
  const int rc = std::system((cmd + " >/dev/null").c_str());
  log = cmd;
  return rc == 0;
}

// Runs fuzzylite on `fis_path` for `inputs`; resolution 0 keeps fuzzylite's
// default (100). Returns the output columns of each row.
Rows fuzzyliteEval(const std::string& fis_path, const Rows& inputs, int resolution, const TempDir& tmp,
                   std::size_t n_out) {
  {
    std::ofstream in(tmp / "inputs.fld");
    char buf[64];
    for (const auto& row : inputs) {
      for (std::size_t i = 0; i < row.size(); ++i) {
        std::snprintf(buf, sizeof buf, "%.17g", row[i]);
        in << (i ? " " : "") << buf;
      }
      in << '\n';
    }
  }
  std::string engine = fis_path, format = "fis", log;
  if (resolution > 0) {
    const std::string fll = (tmp / "engine.fll").string();
    const std::string cmd = "fuzzylite -i '" + fis_path + "' -if fis -of fll -o '" + fll + "' -decimals 17";
    if (!run(cmd, log)) {
      ADD_FAILURE() << "failed: " << log;
      return {};
    }
    // fll "defuzzifier: Centroid 100" -> the matched resolution.
    const std::string text = std::regex_replace(
        readAll(fll), std::regex(R"((defuzzifier: (Centroid|Bisector|MeanOfMaximum|SmallestOfMaximum|LargestOfMaximum)) 100)"),
        "$1 " + std::to_string(resolution));
    std::ofstream(fll) << text;
    engine = fll;
    format = "fll";
  }
  const std::string out = (tmp / "outputs.fld").string();
  const std::string cmd = "fuzzylite -i '" + engine + "' -if " + format + " -of fld -d '" + (tmp / "inputs.fld").string() +
                          "' -o '" + out + "' -decimals 12 -dheader false -dinputs true";
  if (!run(cmd, log)) {
    ADD_FAILURE() << "failed: " << log;
    return {};
  }
  Rows rows = parseRows(readAll(out));
  if (rows.size() != inputs.size()) {
    ADD_FAILURE() << "fuzzylite returned " << rows.size() << " rows for " << inputs.size() << " inputs (" << cmd << ")";
    return {};
  }
  Rows outputs;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto& row = rows[r];
    if (row.size() != inputs[r].size() + n_out) {
      ADD_FAILURE() << "fuzzylite row " << r << " has " << row.size() << " columns";
      return {};
    }
    for (std::size_t i = 0; i < inputs[r].size(); ++i) {
      if (std::abs(row[i] - inputs[r][i]) > 1e-9 * std::max(1.0, std::abs(inputs[r][i]))) {
        ADD_FAILURE() << "fuzzylite row " << r << " is not the row we sent";
        return {};
      }
    }
    outputs.emplace_back(row.begin() + static_cast<std::ptrdiff_t>(inputs[r].size()), row.end());
  }
  return outputs;
}

class FuzzyliteReference : public ::testing::TestWithParam<RefCase> {};

TEST_P(FuzzyliteReference, AgreesWithinSamplingResolution) {
  ASSERT_TRUE(haveFuzzylite()) << kMissing;
  const RefCase& c = GetParam();
  const std::string path = inspect::test::srcPath("") + c.file;
  const Fis fis = readFisFile(path);
  const Rows inputs = inputGrid(fis, c.offset_only);
  const bool mamdani = fis.type == FisType::kMamdani;
  const std::string tag = fs::path(c.file).stem().string();
  TempDir tmp(tag);

  // Tolerances (Mamdani) in sample steps of the output range; see docs/fuzzy.md.
  // Centroid, mom, som, lom: one step (the two tools' sample grids are offset
  // by half a step and MATLAB's includes both range ends at full weight).
  // Bisector: three steps (MATLAB takes the first sample at or past half the
  // area, fuzzylite interpolates between two running sums).
  const double steps = fis.defuzz_method == DefuzzMethod::kBisector ? 3.0 : 1.0;
  struct Mode {
    const char* name;
    int fl_resolution;    // 0 = fuzzylite default (100)
    std::size_t samples;  // our sample points
  };
  std::vector<Mode> modes{{"default", 0, 101}};
  if (mamdani) modes.push_back({"matched", kMatchedResolution, kMatchedSamples});

  for (const Mode& m : modes) {
    SCOPED_TRACE(m.name);
    const Rows ref = fuzzyliteEval(path, inputs, m.fl_resolution, tmp, fis.outputs.size());
    ASSERT_EQ(ref.size(), inputs.size());
    EngineOptions opt;
    opt.num_samples = m.samples;
    Engine engine(fis, opt);
    std::vector<double> out(fis.outputs.size()), view(fis.outputs.size());

    // fuzzylite does not fire a rule whose strength is below its macheps
    // (1e-6); MATLAB does. Our value with those rules switched off (weight 0),
    // or nullopt when no rule is that weak.
    auto fuzzyliteView = [&](const std::vector<double>& in) -> bool {
      engine.evaluate(in, out);
      Fis weak = fis;
      bool any = false;
      const auto strengths = engine.firingStrengths();
      for (std::size_t r = 0; r < strengths.size(); ++r) {
        if (strengths[r] > 0.0 && strengths[r] < kFuzzyliteMacheps) {
          weak.rules[r].weight = 0.0;
          any = true;
        }
      }
      if (!any) return false;
      Engine(weak, opt).evaluate(in, view);
      return true;
    };

    for (std::size_t o = 0; o < fis.outputs.size(); ++o) {
      const Variable& v = fis.outputs[o];
      const double res = m.fl_resolution > 0 ? m.fl_resolution : 100.0;
      const double tol = mamdani ? steps * (v.max - v.min) / res : 1e-9;
      double max_diff = 0.0, raw_max_diff = 0.0;
      std::size_t compared = 0, no_rule = 0, weak_rows = 0, failures = 0;
      for (std::size_t r = 0; r < inputs.size(); ++r) {
        engine.evaluate(inputs[r], out);
        const double ours = out[o];
        const double fl = ref[r][o];
        if (std::isnan(fl)) {
          // fuzzylite has no value when nothing fires; MATLAB (and we) give mid-range.
          ++no_rule;
          if (ours != engine.noRuleValue(o)) {
            ASSERT_TRUE(fuzzyliteView(inputs[r])) << "row " << r << ": fuzzylite nan, ours " << ours;
            EXPECT_DOUBLE_EQ(view[o], engine.noRuleValue(o)) << "row " << r;
            ++weak_rows;
          }
          continue;
        }
        ++compared;
        const double scale = mamdani ? 1.0 : std::max(1.0, std::abs(fl));
        double d = std::abs(ours - fl);
        raw_max_diff = std::max(raw_max_diff, d / scale);
        if (fuzzyliteView(inputs[r])) {
          // Compare what fuzzylite computes: these rules fire for MATLAB only.
          d = std::abs(view[o] - fl);
          ++weak_rows;
        }
        max_diff = std::max(max_diff, d / scale);
        if (d > tol * scale && ++failures <= 5) {
          ADD_FAILURE() << tag << " " << m.name << " output " << v.name << " at (" << inputs[r][0] << ", "
                        << inputs[r][1] << "): ours " << ours << ", fuzzylite " << fl << ", |diff| " << d
                        << " > tol " << tol * scale;
        }
      }
      std::printf("REF %-22s %-7s %-4s rows %4zu no-rule %2zu weak %3zu  max|diff| %.3g (raw %.3g)  tol %.3g%s\n",
                  tag.c_str(), m.name, v.name.c_str(), compared, no_rule, weak_rows, max_diff, raw_max_diff, tol,
                  mamdani ? "" : " (relative)");
      EXPECT_GT(compared, inputs.size() / 2) << "too few rows fired to compare";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Files, FuzzyliteReference,
                         ::testing::Values(RefCase{"config/fuzzy/fuzzy_pid.fis", false},
                                           RefCase{"tests/shared/fuzzy/data/shapes_centroid.fis", false},
                                           RefCase{"tests/shared/fuzzy/data/shapes_bisector.fis", false},
                                           RefCase{"tests/shared/fuzzy/data/shapes_probor_centroid.fis", false},
                                           RefCase{"tests/shared/fuzzy/data/shapes_sum_centroid.fis", false},
                                           RefCase{"tests/shared/fuzzy/data/peak_mom.fis", true},
                                           RefCase{"tests/shared/fuzzy/data/peak_som.fis", false},
                                           RefCase{"tests/shared/fuzzy/data/peak_lom.fis", false},
                                           RefCase{"tests/shared/fuzzy/data/sugeno_wtaver.fis", false},
                                           RefCase{"tests/shared/fuzzy/data/sugeno_wtsum.fis", false}),
                         [](const ::testing::TestParamInfo<RefCase>& i) {
                           return fs::path(i.param.file).stem().string();
                         });

TEST(FuzzyliteReferenceTool, IsInstalled) { ASSERT_TRUE(haveFuzzylite()) << kMissing; }

}  // namespace
}  // namespace inspect::fuzzy
