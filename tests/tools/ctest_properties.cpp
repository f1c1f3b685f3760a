// ctest_properties: reads `ctest --show-only=json-v1` on stdin and checks that
// every test has a TIMEOUT and exactly one kind label (unit, stack, bench,
// long, fuzz or sanitize: its phase in scripts/test.sh, tests/InspectTest.cmake),
// and a name no other test has (a unit test is named after its gtest suite:
// two programs with a suite of the same name would run only one of them);
// otherwise a test could hang CI or silently never run. Prints what is wrong;
// exit status 1 when anything is.
#include <cstdio>
#include <iostream>
#include <iterator>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

int main() {
  const std::string text((std::istreambuf_iterator<char>(std::cin)), std::istreambuf_iterator<char>());
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ctest_properties: stdin is not ctest's JSON: %s\n", e.what());
    return 1;
  }
  const std::set<std::string> kinds = {"unit", "stack", "bench", "package", "long", "fuzz", "sanitize"};
  int bad = 0, n = 0;
  std::set<std::string> names;
  for (const auto& t : j.value("tests", nlohmann::json::array())) {
    ++n;
    const std::string name = t.value("name", "?");
    if (!names.insert(name).second) std::printf("%s: two tests of this name\n", name.c_str()), ++bad;
    double timeout = 0;
    int found = 0;
    for (const auto& p : t.value("properties", nlohmann::json::array())) {
      if (p.value("name", "") == "TIMEOUT" && p["value"].is_number()) timeout = p["value"].get<double>();
      if (p.value("name", "") == "LABELS")
        for (const auto& l : p["value"])
          if (l.is_string() && kinds.count(l.get<std::string>())) ++found;
    }
    if (timeout <= 0) std::printf("%s: no TIMEOUT\n", name.c_str()), ++bad;
    if (found != 1) std::printf("%s: %d kind labels, wanted exactly one\n", name.c_str(), found), ++bad;
  }
  if (n == 0) std::printf("no tests in ctest's JSON\n"), ++bad;
  std::printf("ctest_properties: %d tests, %d problems (declare tests with tests/InspectTest.cmake)\n", n, bad);
  return bad ? 1 : 0;
}
