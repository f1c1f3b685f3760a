// Fuzzes the MATLAB .fis reader (shared/fuzzy/fis_reader) and what is done
// with a system it accepts: the engine is built and evaluated (inside,
// outside and at the edges of the ranges, NaN), the system is written back
// (fis_writer) and read again, and a small lookup surface is compiled.
// Fuzzy systems arrive from config/fuzzy/ and over the link (a GainsUpdate
// may carry .fis text), so the reader must refuse anything broken with a
// FisError and never crash.
//
// Input: the .fis text.
// Invariants: an accepted system builds an Engine (parseFis validates);
// formatFis(fis) parses back to an equal Fis; evaluate() gives finite
// outputs for finite inputs.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>
#include <vector>

#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/fis_writer.hpp"
#include "shared/fuzzy/lookup_surface.hpp"
#include "tests/fuzz/fuzz_records.hpp"

using namespace inspect::fuzzy;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size > 64 * 1024) return 0;  // the robot refuses larger pushed systems
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  Fis fis;
  try {
    fis = parseFis(text, "fuzz.fis");
  } catch (const FisError& e) {
    FUZZ_CHECK(std::string_view(e.what()).starts_with("fuzz.fis"));
    return 0;
  }
  FUZZ_CHECK(fisProblems(fis).empty());

  // Written and read back: the same system.
  const std::string again = formatFis(fis);
  Fis back;
  try {
    back = parseFis(again, "again.fis");
  } catch (const FisError& e) {
    std::fprintf(stderr, "formatFis output refused: %s\n--- text ---\n%s\n", e.what(), again.c_str());
    FUZZ_CHECK(!"formatFis output parses");
  }
  FUZZ_CHECK(back == fis);

  // Bound the work of one input: the engine samples each Mamdani output.
  if (fis.inputs.size() > 8 || fis.outputs.size() > 8 || fis.rules.size() > 512) return 0;
  Engine engine(fis, {.num_samples = 101, .clip_inputs = (size & 1) != 0});
  std::vector<double> in(engine.numInputs()), out(engine.numOutputs());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Moderate numbers everywhere: then finite inputs in range give numbers out
  // (huge parameters may overflow to inf - inf legitimately).
  double largest = 0.0;
  for (const auto* vars : {&fis.inputs, &fis.outputs})
    for (const auto& v : *vars) {
      largest = std::max({largest, std::abs(v.min), std::abs(v.max)});
      for (const auto& mf : v.mfs)
        for (double p : mf.params) largest = std::max(largest, std::abs(p));
    }
  const bool moderate = largest < 1e100;
  for (int k = 0; k < 7; ++k) {
    for (std::size_t i = 0; i < in.size(); ++i) {
      const auto& v = fis.inputs[i];
      const double span = v.max - v.min;
      // k < 4: inside the range (ends included); then outside it.
      const double pick[7] = {v.min, v.max, v.min + span / 2, v.min + span * 0.37, v.min - span, v.max + span, 1e300};
      in[i] = pick[k < 4 ? (k + i) % 4 : 4 + (k + i) % 3];
    }
    const EvalStatus st = engine.evaluate(in, out);
    bool finite_in = true;
    for (double x : in) finite_in = finite_in && std::isfinite(x);
    if (moderate && k < 4 && finite_in && (st == EvalStatus::kOk || st == EvalStatus::kNoRuleFired))
      for (double y : out) FUZZ_CHECK(!std::isnan(y));
  }
  in.assign(in.size(), nan);
  FUZZ_CHECK(engine.evaluate(in, out) == EvalStatus::kNonFiniteInput);
  std::vector<double> wrong(in.size() + 1, 0.0);
  FUZZ_CHECK(engine.evaluate(wrong, out) == EvalStatus::kBadSize);

  if (fis.inputs.size() <= LookupSurface::kMaxInputs && fis.rules.size() <= 64) {
    const LookupSurface surface(fis, {.points_per_input = 5});
    std::vector<double> mid(fis.inputs.size());
    for (std::size_t i = 0; i < mid.size(); ++i) mid[i] = (fis.inputs[i].min + fis.inputs[i].max) / 2;
    (void)surface.evaluate(mid, out);
  }
  return 0;
}
