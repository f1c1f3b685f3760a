// .fis reading and writing: errors name the file, the line and the problem;
// write -> read gives an equal Fis and write(read(file)) is stable.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shared/fuzzy/fis_error.hpp"
#include "shared/fuzzy/fis_reader.hpp"
#include "shared/fuzzy/fis_writer.hpp"
#include "tests/support/paths.hpp"

namespace inspect::fuzzy {
namespace {


// A valid system; the comments give the line numbers the cases below use.
const std::string kBase =
    "[System]\n"                          // 1
    "Name='t'\n"                          // 2
    "Type='mamdani'\n"                    // 3
    "Version=2.0\n"                       // 4
    "NumInputs=2\n"                       // 5
    "NumOutputs=1\n"                      // 6
    "NumRules=2\n"                        // 7
    "AndMethod='min'\n"                   // 8
    "OrMethod='max'\n"                    // 9
    "ImpMethod='min'\n"                   // 10
    "AggMethod='max'\n"                   // 11
    "DefuzzMethod='centroid'\n"           // 12
    "\n"                                  // 13
    "[Input1]\n"                          // 14
    "Name='a'\n"                          // 15
    "Range=[0 10]\n"                      // 16
    "NumMFs=3\n"                          // 17
    "MF1='lo':'trimf',[-5 0 5]\n"         // 18
    "MF2='mid':'trimf',[0 5 10]\n"        // 19
    "MF3='hi':'trimf',[5 10 15]\n"        // 20
    "\n"                                  // 21
    "[Input2]\n"                          // 22
    "Name='b'\n"                          // 23
    "Range=[0 1]\n"                       // 24
    "NumMFs=3\n"                          // 25
    "MF1='lo':'gaussmf',[0.2 0]\n"        // 26
    "MF2='mid':'gaussmf',[0.2 0.5]\n"     // 27
    "MF3='hi':'gaussmf',[0.2 1]\n"        // 28
    "\n"                                  // 29
    "[Output1]\n"                         // 30
    "Name='y'\n"                          // 31
    "Range=[0 1]\n"                       // 32
    "NumMFs=2\n"                          // 33
    "MF1='lo':'trimf',[-1 0 1]\n"         // 34
    "MF2='hi':'trimf',[0 1 2]\n"          // 35
    "\n"                                  // 36
    "[Rules]\n"                           // 37
    "1 1, 1 (1) : 1\n"                    // 38
    "3 2, 2 (1) : 1\n";                   // 39

std::string edit(const std::string& from, const std::string& to) {
  std::string t = kBase;
  const auto pos = t.find(from);
  if (pos == std::string::npos) ADD_FAILURE() << "edit target not found: " << from;
  else t.replace(pos, from.size(), to);
  return t;
}

std::string loadError(const std::string& text) {
  try {
    parseFis(text, "speed.fis");
  } catch (const FisError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(FisReader, BaseSystemLoads) {
  const Fis f = parseFis(kBase, "speed.fis");
  EXPECT_EQ(f.name, "t");
  ASSERT_EQ(f.inputs.size(), 2u);
  EXPECT_EQ(f.inputs[1].mfs[2].name, "hi");
  EXPECT_EQ(f.inputs[1].mfs[2].type, MfType::kGaussmf);
  EXPECT_EQ(f.inputs[1].mfs[2].params, (std::vector<double>{0.2, 1}));
  ASSERT_EQ(f.rules.size(), 2u);
  EXPECT_EQ(f.rules[1].antecedent, (std::vector<int>{3, 2}));
  EXPECT_EQ(f.rules[1].consequent, (std::vector<int>{2}));
}

struct ErrorCase {
  const char* label;
  std::string text;
  const char* expected;  // the whole "file:line: message" prefix or a substring of it
};

void PrintTo(const ErrorCase& c, std::ostream* os) { *os << c.label; }

class FisReaderError : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(FisReaderError, NamesFileLineAndProblem) {
  const ErrorCase& c = GetParam();
  const std::string msg = loadError(c.text);
  EXPECT_NE(msg.find(c.expected), std::string::npos) << "expected: " << c.expected << "\n     got: " << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, FisReaderError,
    ::testing::Values(
        ErrorCase{"param count", edit("[5 10 15]", "[5 10]"), "speed.fis:20: MF3: trimf needs 3 parameters, got 2"},
        ErrorCase{"rule refers to missing MF", edit("3 2, 2 (1) : 1", "3 9, 2 (1) : 1"),
                  "speed.fis:39: rule 2 refers to MF 9 of input 2, which has 3"},
        ErrorCase{"negated missing MF", edit("1 1, 1 (1) : 1", "-4 1, 1 (1) : 1"),
                  "speed.fis:38: rule 1 refers to MF 4 of input 1, which has 3"},
        ErrorCase{"output MF missing", edit("3 2, 2 (1) : 1", "3 2, 3 (1) : 1"),
                  "speed.fis:39: rule 2 refers to MF 3 of output 1, which has 2"},
        ErrorCase{"sigma zero", edit("[0.2 0.5]", "[0 0.5]"), "speed.fis:27: MF2: gaussmf [sigma c] needs sigma > 0"},
        ErrorCase{"trimf order", edit("[0 5 10]", "[5 0 10]"), "speed.fis:19: MF2: trimf [a b c] needs a <= b <= c"},
        ErrorCase{"range reversed", edit("Range=[0 1]\nNumMFs=3", "Range=[1 0]\nNumMFs=3"),
                  "speed.fis:24: Range needs two finite numbers with min < max"},
        ErrorCase{"range count", edit("Range=[0 10]", "Range=[0 10 20]"), "speed.fis:16: Range needs 2 numbers"},
        ErrorCase{"range not a number", edit("Range=[0 10]", "Range=[0 ten]"), "speed.fis:16: Range: 'ten' is not a number"},
        ErrorCase{"NumRules mismatch", edit("NumRules=2", "NumRules=3"), "speed.fis:7: NumRules=3 but [Rules] has 2 rules"},
        ErrorCase{"unknown MF type", edit("'trimf',[0 5 10]", "'foomf',[0 5 10]"),
                  "speed.fis:19: MF2: unsupported membership function type 'foomf'"},
        ErrorCase{"NumMFs too big", edit("NumMFs=2", "NumMFs=3"), "speed.fis:30: [Output1] has NumMFs=3 but no MF3"},
        ErrorCase{"MF beyond NumMFs", edit("MF2='hi':'trimf',[0 1 2]", "MF4='hi':'trimf',[0 1 2]"),
                  "speed.fis:35: MF4: NumMFs is 2"},
        ErrorCase{"missing input section", edit("NumInputs=2", "NumInputs=3"),
                  "speed.fis:5: NumInputs=3 but there is no [Input3]"},
        ErrorCase{"section beyond count", edit("NumOutputs=1", "NumOutputs=0"), "speed.fis:30: [Output1]: NumOutputs is 0"},
        ErrorCase{"unknown key", edit("Name='b'", "Name='b'\nColour='red'"), "speed.fis:24: unknown key 'Colour' in [Input2]"},
        ErrorCase{"unknown section", edit("[Rules]", "[Notes]\n[Rules]"), "speed.fis:37: unknown section [Notes]"},
        ErrorCase{"duplicate key", edit("Name='b'", "Name='b'\nName='c'"), "speed.fis:24: Name appears twice in [Input2]"},
        ErrorCase{"unsupported method", edit("AndMethod='min'", "AndMethod='einstein'"),
                  "speed.fis:8: AndMethod: unsupported 'einstein' (supported: min, prod)"},
        ErrorCase{"unsupported type", edit("Type='mamdani'", "Type='tsukamoto'"), "speed.fis:3: Type: unsupported 'tsukamoto'"},
        ErrorCase{"missing key", edit("DefuzzMethod='centroid'\n", ""), "speed.fis:1: [System] has no DefuzzMethod="},
        ErrorCase{"not quoted", edit("Name='t'", "Name=t"), "speed.fis:2: Name: expected a quoted 'text'"},
        ErrorCase{"rule input count", edit("1 1, 1 (1) : 1", "1, 1 (1) : 1"),
                  "speed.fis:38: rule 1 has 1 antecedent entries, the system has 2 inputs"},
        ErrorCase{"rule weight", edit("3 2, 2 (1) : 1", "3 2, 2 (1.5) : 1"), "speed.fis:39: rule 2: weight must lie in [0, 1]"},
        ErrorCase{"rule connection", edit("3 2, 2 (1) : 1", "3 2, 2 (1) : 3"),
                  "speed.fis:39: rule 2: connection must be 1 (AND) or 2 (OR), got '3'"},
        ErrorCase{"rule index not a number", edit("3 2, 2 (1) : 1", "3 x, 2 (1) : 1"),
                  "speed.fis:39: rule 2: 'x' is not a membership function index"},
        ErrorCase{"rule hedge index", edit("3 2, 2 (1) : 1", "3 2.2, 2 (1) : 1"),
                  "speed.fis:39: rule 2: '2.2' is not a whole membership function index"},
        ErrorCase{"rule without comma", edit("3 2, 2 (1) : 1", "3 2 2 (1) : 1"), "speed.fis:39: rule 2: no ','"},
        ErrorCase{"rule without antecedent", edit("3 2, 2 (1) : 1", "0 0, 2 (1) : 1"),
                  "speed.fis:39: rule 2 has no antecedent"},
        ErrorCase{"Sugeno MF in Mamdani", edit("MF2='hi':'trimf',[0 1 2]", "MF2='hi':'constant',[1]"),
                  "speed.fis:35: MF2: 'constant' is only allowed for outputs of a Sugeno system"},
        ErrorCase{"Mamdani MF in Sugeno", edit("Type='mamdani'", "Type='sugeno'"),
                  "speed.fis:12: a Sugeno system needs DefuzzMethod 'wtaver' or 'wtsum'"},
        ErrorCase{"duplicate MF name", edit("MF2='mid':'trimf'", "MF2='lo':'trimf'"),
                  "speed.fis:19: MF2: name 'lo' is already used by MF1"},
        ErrorCase{"duplicate variable", edit("Name='b'", "Name='a'"), "speed.fis:23: variable name 'a' is used twice"},
        ErrorCase{"text before System", "hello\n" + kBase, "speed.fis:1: text before the first section"},
        ErrorCase{"no System", "[Rules]\n1 1, 1 (1) : 1\n", "speed.fis:1: no [System] section"},
        ErrorCase{"bad MF syntax", edit("MF1='lo':'trimf',[-5 0 5]", "MF1='lo','trimf',[-5 0 5]"),
                  "speed.fis:18: MF1: expected 'name':'type',[parameters]"}));

TEST(FisReader, MissingFileIsOneLineError) {
  try {
    readFisFile("/nonexistent/dir/x.fis");
    FAIL() << "no error";
  } catch (const FisError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/dir/x.fis: cannot open file");
  }
}

TEST(FisReader, CommentsBeforeSystemAreKeptOthersSkipped) {
  const Fis f = parseFis("% first\n#second\n// third\n" + edit("[Rules]", "% inside\n[Rules]\n# rule comment"), "c.fis");
  EXPECT_EQ(f.comments, (std::vector<std::string>{"first", "second", "third"}));
  EXPECT_EQ(f.rules.size(), 2u);
}

TEST(FisReader, AcceptsCrLfAndMatlabExtras) {
  std::string t = edit("DefuzzMethod='centroid'\n", "DefuzzMethod='centroid'\nDisableStructuralChecks=0\n");
  std::string crlf;
  for (char ch : t) {
    if (ch == '\n') crlf += '\r';
    crlf += ch;
  }
  const Fis f = parseFis(crlf, "crlf.fis");
  ASSERT_TRUE(f.disable_structural_checks.has_value());
  EXPECT_EQ(*f.disable_structural_checks, 0);
  EXPECT_EQ(f.inputs[0].max, 10.0);
}

TEST(FisReader, ReadsFuzzyliteExportedFiles) {
  // fuzzylite's FisExporter writes "Version=6.0", decimals everywhere and
  // rule indices as "1.000 -2.000 , 1.000 (1.000) : 1".
  std::string text = edit("Range=[0 10]", "Range=[0.000 10.000]");
  text.replace(text.find("1 1, 1 (1) : 1"), 14, "1.000 -1.000 , 1.000 (0.500) : 2");
  const Fis f = parseFis("#Code automatically generated with fuzzylite 6.0.\n\n" + text, "fl.fis");
  EXPECT_EQ(f.rules[0].antecedent, (std::vector<int>{1, -1}));
  EXPECT_EQ(f.rules[0].consequent, (std::vector<int>{1}));
  EXPECT_EQ(f.rules[0].weight, 0.5);
  EXPECT_EQ(f.rules[0].connection, Connection::kOr);
  EXPECT_EQ(f.comments, (std::vector<std::string>{"Code automatically generated with fuzzylite 6.0."}));
}

TEST(CheckComplete, NamesVariableForSystemsBuiltInCode) {
  Fis f = parseFis(kBase, "x.fis");
  f.inputs[1].mfs[0].params = {-1.0, 0.0};
  try {
    checkComplete(f);
    FAIL() << "no error";
  } catch (const FisError& e) {
    EXPECT_STREQ(e.what(), "fis 't': input 2 'b': MF1: gaussmf [sigma c] needs sigma > 0, got -1");
  }
  f = parseFis(kBase, "x.fis");
  f.rules.clear();
  EXPECT_THROW(checkComplete(f), FisError);
}

std::vector<std::string> fisFiles() {
  std::vector<std::string> files{inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis")};
  for (const auto& e : std::filesystem::directory_iterator(inspect::test::srcPath("tests/shared/fuzzy/data"))) {
    if (e.path().extension() == ".fis") files.push_back(e.path().string());
  }
  return files;
}

TEST(FisRoundTrip, EveryShippedAndTestFileIsLossless) {
  const auto files = fisFiles();
  ASSERT_GE(files.size(), 8u);
  for (const auto& path : files) {
    SCOPED_TRACE(path);
    const Fis a = readFisFile(path);
    const std::string text = formatFis(a);
    const Fis b = parseFis(text, "written.fis");
    EXPECT_EQ(a, b);
    EXPECT_EQ(formatFis(b), text) << "write(read(write(read(file)))) differs";
  }
}

TEST(FisRoundTrip, AwkwardNumbersSurviveExactly) {
  Fis a = parseFis(kBase, "x.fis");
  a.inputs[0].min = -0.1;
  a.inputs[0].max = 1e-300 + 10.0 / 3.0;
  a.inputs[1].mfs[0].params = {0.1 + 0.2, 1.0 / 3.0};
  a.outputs[0].mfs[0].params = {-1e5, 2.5e-7, 123456.789012345};
  a.rules[0].weight = 0.3;
  a.rules[1].antecedent = {-2, 0};
  a.rules[1].connection = Connection::kOr;
  a.name = "awkward name";
  a.comments = {"a comment", ""};
  const Fis b = parseFis(formatFis(a), "y.fis");
  EXPECT_EQ(a, b);
}

TEST(FisRoundTrip, WritesAFileThatReadsBack) {
  const Fis a = readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis"));
  const auto path = std::filesystem::temp_directory_path() / "inspect_fuzzy_roundtrip.fis";
  writeFisFile(a, path.string());
  EXPECT_EQ(readFisFile(path.string()), a);
  std::filesystem::remove(path);
}

TEST(ShippedFuzzyPid, HasThePapersStructure) {
  const Fis f = readFisFile(inspect::test::srcPath("config/fuzzy/fuzzy_pid.fis"));
  EXPECT_EQ(f.type, FisType::kMamdani);
  EXPECT_EQ(f.and_method, AndMethod::kMin);
  EXPECT_EQ(f.or_method, OrMethod::kMax);
  EXPECT_EQ(f.imp_method, ImpMethod::kMin);
  EXPECT_EQ(f.agg_method, AggMethod::kMax);
  EXPECT_EQ(f.defuzz_method, DefuzzMethod::kCentroid);
  ASSERT_EQ(f.inputs.size(), 2u);
  ASSERT_EQ(f.outputs.size(), 3u);
  EXPECT_EQ(f.rules.size(), 49u);
  const std::vector<std::string> terms{"NB", "NM", "NS", "ZO", "PS", "PM", "PB"};
  for (const auto* vars : {&f.inputs, &f.outputs}) {
    for (const auto& v : *vars) {
      EXPECT_EQ(v.min, -3.0);
      EXPECT_EQ(v.max, 3.0);
      ASSERT_EQ(v.mfs.size(), 7u);
      for (std::size_t j = 0; j < 7; ++j) {
        EXPECT_EQ(v.mfs[j].name, terms[j]);
        EXPECT_EQ(v.mfs[j].type, vars == &f.inputs ? MfType::kGaussmf : MfType::kTrimf);
      }
    }
  }
  // Neighbouring input terms cross at (close to) 0.5, halfway between centres.
  const auto& nb = f.inputs[0].mfs[0];
  EXPECT_NEAR(mfValue(nb.type, nb.params, -2.5), 0.5, 1e-3);
  // Every (e, ec) pair has exactly one rule.
  std::vector<int> seen(49, 0);
  for (const auto& r : f.rules) seen[static_cast<std::size_t>((r.antecedent[0] - 1) * 7 + r.antecedent[1] - 1)]++;
  for (int s : seen) EXPECT_EQ(s, 1);
  bool cites = false;
  for (const auto& c : f.comments) cites = cites || c.find("Liu Jinkun") != std::string::npos;
  EXPECT_TRUE(cites) << "the rule tables' source must be cited in the file header";
}

}  // namespace
}  // namespace inspect::fuzzy
