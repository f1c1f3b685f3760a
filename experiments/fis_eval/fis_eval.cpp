// fis_eval: evaluates a MATLAB .fis file on rows of inputs read from stdin
// (fuzzylite .fld layout) and prints one row of outputs per row.
#include <charconv>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "shared/util/cli_args.hpp"
#include "shared/fuzzy/engine.hpp"
#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"

namespace {

constexpr const char* kUsage =
    "usage: fis_eval [--samples N] [--clip] [--header] FILE.fis < inputs\n"
    "\n"
    "Evaluates the fuzzy inference system FILE.fis (MATLAB .fis format) with\n"
    "MATLAB evalfis semantics. Reads rows of space-separated input values from\n"
    "stdin, one row per line, one column per input in order (the layout of a\n"
    "fuzzylite .fld file). Blank lines and lines starting with '#' are skipped;\n"
    "a first line that is not numeric (a header of names) is skipped too.\n"
    "Prints one row of space-separated outputs per input row (%.10g; 'nan' for\n"
    "a non-finite input).\n"
    "\n"
    "  --samples N  points at which Mamdani outputs are sampled (default 101, as MATLAB)\n"
    "  --clip       clip inputs to their ranges (MATLAB and fuzzylite do not)\n"
    "  --header     print a header line with the output names first\n"
    "  --help       this text\n"
    "\n"
    "A bad row gets a message on stderr naming its line and is skipped.\n"
    "Exit status: 0 all rows evaluated, 1 some rows were bad, 2 usage or\n"
    "the file could not be loaded (one line on stderr).\n";

enum class RowParse { kOk, kNotNumeric, kEmpty };

RowParse parseRow(std::string_view line, std::vector<double>& values, std::string& bad_token) {
  values.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == ',' || line[i] == '\r')) ++i;
    if (i >= line.size()) break;
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != ',' && line[j] != '\r') ++j;
    std::string_view tok = line.substr(i, j - i);
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
    double v = 0;
    auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (ec != std::errc() || p != tok.data() + tok.size()) {
      bad_token = std::string(line.substr(i, j - i));
      return RowParse::kNotNumeric;
    }
    values.push_back(v);
    i = j;
  }
  return values.empty() ? RowParse::kEmpty : RowParse::kOk;
}

}  // namespace

int main(int argc, char** argv) {
  std::string path;
  inspect::fuzzy::EngineOptions options;
  bool header = false;
  inspect::cli::readOrExit("fis_eval", argc, argv, [&](inspect::cli::ArgReader& a) {
    if (a.isHelp()) {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else if (a.is("--clip")) {
      options.clip_inputs = true;
    } else if (a.is("--header")) {
      header = true;
    } else if (a.is("--samples")) {
      options.num_samples = static_cast<std::size_t>(a.integer(3, 1000000));
    } else if (a.isPositional() && path.empty()) {
      path = a.flag();
    } else if (a.isPositional()) {
      throw inspect::cli::UsageError("only one FILE.fis is accepted (see --help)");
    } else {
      a.unknown();
    }
  });
  if (path.empty()) {
    std::fputs("fis_eval: no FILE.fis given (see --help)\n", stderr);
    return 2;
  }

  std::optional<inspect::fuzzy::Engine> engine;
  try {
    engine.emplace(inspect::fuzzy::readFisFile(path), options);
  } catch (const inspect::fuzzy::FisError& e) {
    std::fprintf(stderr, "fis_eval: %s\n", e.what());
    return 2;
  }

  const std::size_t n_in = engine->numInputs();
  std::vector<double> in;
  std::vector<double> out(engine->numOutputs());
  if (header) {
    for (std::size_t o = 0; o < out.size(); ++o) {
      std::fputs(o ? " " : "", stdout);
      std::fputs(engine->fis().outputs[o].name.c_str(), stdout);
    }
    std::fputc('\n', stdout);
  }
  std::string line;
  long line_no = 0;
  bool first_data_line = true;
  bool any_bad = false;
  std::string bad_token;
  while (std::getline(std::cin, line)) {
    ++line_no;
    const auto start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    const RowParse r = parseRow(line, in, bad_token);
    const bool was_first = first_data_line;
    first_data_line = false;
    if (r == RowParse::kNotNumeric) {
      if (was_first) continue;  // a header of names
      std::fprintf(stderr, "fis_eval: line %ld: '%s' is not a number; row skipped\n", line_no, bad_token.c_str());
      any_bad = true;
      continue;
    }
    if (in.size() != n_in) {
      std::fprintf(stderr, "fis_eval: line %ld: expected %zu input value%s, got %zu; row skipped\n", line_no, n_in,
                   n_in == 1 ? "" : "s", in.size());
      any_bad = true;
      continue;
    }
    engine->evaluate(in, out);
    for (std::size_t o = 0; o < out.size(); ++o) std::printf(o ? " %.10g" : "%.10g", out[o]);
    std::fputc('\n', stdout);
  }
  std::fflush(stdout);
  return any_bad ? 1 : 0;
}
