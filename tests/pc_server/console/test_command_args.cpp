// The console's argument grammar: one table per command gives the syntax, the
// argument errors and completion (pc_server/console/command_args.hpp).
#include <gtest/gtest.h>

#include "pc_server/console/command_args.hpp"

using namespace inspect::server;
using namespace inspect::server::args;

namespace {

std::string errorOf(const std::string& cmd, const std::vector<CommandForm>& forms, const std::string& line) {
  const auto r = parseCommandArgs(cmd, forms, line);
  const auto* e = std::get_if<std::string>(&r);
  return e ? *e : "(parsed)";
}

CommandArgs parsed(const std::vector<CommandForm>& forms, const std::string& line) {
  auto r = parseCommandArgs("cmd", forms, line);
  EXPECT_TRUE(std::holds_alternative<CommandArgs>(r)) << line << ": " << std::get<std::string>(r);
  return std::holds_alternative<CommandArgs>(r) ? std::get<CommandArgs>(r) : CommandArgs{};
}

const std::vector<CommandForm> kGoto{{number("x_m"), number("y_m"), opt(number("speed_m_s"))}};
const std::vector<CommandForm> kTrack{
    {subcommand("circle", "path"), number("radius_m"), opt(number("speed_m_s")), opt(number("laps")),
     opt(choice("controller", {"fuzzy_pid", "pid", "direct"}, "controller"))},
    {keyword("line"), number("length_m"), opt(number("speed_m_s"))}};
const std::vector<CommandForm> kVideo{{choice("what", {"on", "off"})},
                                      {keyword("res"), wanting(size("size"), "<W>x<H>, even")},
                                      {keyword("fps"), wanting(number("n"), "1 to 120")}};
const std::vector<CommandForm> kPtz{{number("pan_deg"), number("tilt_deg")}, {keyword("home")}};

}  // namespace

TEST(CommandArgs, SyntaxIsGeneratedFromTheForms) {
  EXPECT_EQ(commandSyntax("goto", kGoto), "goto <x_m> <y_m> [speed_m_s]");
  EXPECT_EQ(commandSyntax("track", kTrack),
            "track circle <radius_m> [speed_m_s] [laps] [fuzzy_pid|pid|direct] | track line <length_m> [speed_m_s]");
  EXPECT_EQ(commandSyntax("ptz", kPtz), "ptz <pan_deg> <tilt_deg> | ptz home");
  EXPECT_EQ(commandSyntax("video", kVideo), "video on|off | video res <W>x<H> | video fps <n>");
  EXPECT_EQ(commandSyntax("stop", {CommandForm{}}), "stop");
}

TEST(CommandArgs, CountErrorsSayHowManyOfWhat) {
  EXPECT_EQ(errorOf("goto", kGoto, "1"), "needs two or three numbers: goto <x_m> <y_m> [speed_m_s]");
  EXPECT_EQ(errorOf("goto", kGoto, "1 2 3 4"), "needs two or three numbers: goto <x_m> <y_m> [speed_m_s]");
  EXPECT_EQ(errorOf("stop", {CommandForm{}}, " now"), "takes no arguments");
  EXPECT_EQ(errorOf("status", {{opt(word("robot", "robot id"))}}, "a b"),
            "takes at most one robot id: status [robot]");
  EXPECT_EQ(errorOf("select", {{word("robot", "robot id")}}, ""), "needs one robot id: select <robot>");
  // Arguments of different kinds: the syntax.
  EXPECT_EQ(errorOf("export", {{word("run-id"), keyword("csv"), opt(word("dir"))}}, "r1 pdf"),
            "syntax: export <run-id> csv [dir]");
}

TEST(CommandArgs, ValueErrorsNameTheWord) {
  EXPECT_EQ(errorOf("goto", kGoto, "a 1"), "'a' is not a number");
  EXPECT_EQ(errorOf("goto", kGoto, "1 nan"), "'nan' is not a number");
  EXPECT_EQ(errorOf("goto", kGoto, "1 2 fast"), "'fast' is not a number");  // the optional speed's word
  EXPECT_EQ(errorOf("wait", {{within(number("seconds"), 0, 3600, "s")}}, "-1"), "-1 s is outside [0, 3600]");
  EXPECT_EQ(errorOf("teleop", {{opt(choice("mode", {"step", "hold"}, "mode"))}}, "fast"),
            "unknown mode 'fast' (step or hold)");
  EXPECT_EQ(errorOf("track", kTrack, "circle 3 fast"), "unknown controller 'fast' (fuzzy_pid, pid or direct)");
  EXPECT_EQ(errorOf("n", {{integer("count")}}, "1.5"), "'1.5' is not a whole number");
}

TEST(CommandArgs, SeveralFormsTheFirstWordSelects) {
  EXPECT_EQ(errorOf("video", kVideo, ""), "syntax: video on|off | video res <W>x<H> | video fps <n>");
  EXPECT_EQ(errorOf("video", kVideo, "loud"), "unknown 'loud' (on, off, res or fps)");
  EXPECT_EQ(errorOf("track", kTrack, "square 3"), "unknown path 'square' (circle or line)");
  EXPECT_EQ(errorOf("video", kVideo, "on now"), "syntax: video on|off | video res <W>x<H> | video fps <n>");
  EXPECT_EQ(errorOf("video", kVideo, "fps many"), "fps 'many': want 1 to 120");
  EXPECT_EQ(errorOf("video", kVideo, "res 640"), "res '640': want <W>x<H>, even");
  EXPECT_EQ(errorOf("ptz", kPtz, "10"), "syntax: ptz <pan_deg> <tilt_deg> | ptz home");
  EXPECT_EQ(errorOf("ptz", kPtz, "left up"), "syntax: ptz <pan_deg> <tilt_deg> | ptz home");
}

TEST(CommandArgs, ValuesAreTypedAndNamed) {
  auto a = parsed(kTrack, "circle 3.5 pid");
  EXPECT_EQ(a.form, 0u);
  EXPECT_TRUE(a.has("circle"));
  EXPECT_DOUBLE_EQ(*a.number("radius_m"), 3.5);
  EXPECT_FALSE(a.number("speed_m_s"));
  EXPECT_DOUBLE_EQ(a.number("laps", 1.0), 1.0);
  EXPECT_EQ(a.text("controller"), "pid");
  a = parsed(kTrack, "line 4 0.3");
  EXPECT_EQ(a.form, 1u);
  EXPECT_DOUBLE_EQ(*a.number("speed_m_s"), 0.3);
  a = parsed(kVideo, "res 1280x720");
  EXPECT_DOUBLE_EQ(*a.number("size.w"), 1280);
  EXPECT_DOUBLE_EQ(*a.number("size.h"), 720);
  a = parsed({{integer("n")}}, "0x10");
  EXPECT_DOUBLE_EQ(*a.number("n"), 16);
  // The rest of the line keeps its spacing; words and key=values are lists.
  a = parsed({{subcommand("start"), opt(rest("name"))}}, " start night  round B");
  EXPECT_EQ(a.text("name"), "night  round B");
  a = parsed({{keyword("set"), keyValues("gains", "<name>=<value>...")}}, "set kp=1 ki=2");
  EXPECT_EQ(a.list("gains"), (std::vector<std::string>{"kp=1", "ki=2"}));
  a = parsed({{words("[filters]")}}, "");
  EXPECT_TRUE(a.list("words").empty());
}

TEST(CommandArgs, CompletionOffersWhatMayComeNext) {
  const std::map<ArgSpec::Source, std::vector<std::string>> robots{{ArgSpec::Source::kRobots, {"robot1", "robot2"}}};
  using V = std::vector<std::string>;
  EXPECT_EQ(completeArgs(kTrack, {}, "", robots), (V{"circle", "line"}));
  EXPECT_EQ(completeArgs(kTrack, {}, "c", robots), (V{"circle"}));
  // After a required number: the optional numbers offer nothing, the controller its words.
  EXPECT_EQ(completeArgs(kTrack, {"circle", "3"}, "p", robots), (V{"pid"}));
  EXPECT_EQ(completeArgs(kVideo, {}, "", robots), (V{"fps", "off", "on", "res"}));
  const std::vector<CommandForm> gains{{subcommand("push"), opt(completing(word("robot"), ArgSpec::Source::kRobots))}};
  EXPECT_EQ(completeArgs(gains, {"push"}, "robot", robots), (V{"robot1", "robot2"}));
  EXPECT_TRUE(completeArgs(kGoto, {"1", "2", "3"}, "", robots).empty());
}

TEST(CommandArgs, KeyValuePairsAreCheckedByTheirKeys) {
  const std::vector<CommandForm> tune{
      {subcommand("list")},
      {opt(keyValues("options", "key=value ...",
                     {choice("ref", {"circle", "line"}), within(integer("evals"), 10, 1000), within(number("speed"), 0.1, 2),
                      word("plant")}))}};
  const CommandArgs a = parsed(tune, "evals=20 ref=line speed=0.5 evals=30 plant=run-7");
  EXPECT_EQ(a.form, 1u);
  EXPECT_EQ(a.number("options.evals"), 30.0);  // the last of a key given twice
  EXPECT_EQ(a.text("options.ref"), "line");
  EXPECT_EQ(a.number("options.speed"), 0.5);
  EXPECT_EQ(a.text("options.plant"), "run-7");
  EXPECT_FALSE(a.has("options.radius"));
  EXPECT_EQ(a.list("options").size(), 5u);
  EXPECT_EQ(parsed(tune, "").form, 1u);
  EXPECT_EQ(parsed(tune, "list").form, 0u);
  EXPECT_EQ(errorOf("tune", tune, "frob"), "'frob' is not key=value");
  EXPECT_EQ(errorOf("tune", tune, "colour=red"), "unknown option 'colour' (ref, evals, speed or plant)");
  EXPECT_EQ(errorOf("tune", tune, "evals=5"), "evals=5: expected a number in [10, 1000]");
  EXPECT_EQ(errorOf("tune", tune, "evals=abc"), "evals=abc: expected a number in [10, 1000]");
  EXPECT_EQ(errorOf("tune", tune, "evals=20.5"), "evals=20.5: expected a whole number in [10, 1000]");
  EXPECT_EQ(errorOf("tune", tune, "ref=line ref=spiral"), "ref=spiral: expected circle or line");
  EXPECT_EQ(errorOf("tune", tune, "list extra"), "syntax: tune list | tune [key=value ...]");
  // Completion offers the keys, then a choice's values.
  using V = std::vector<std::string>;
  EXPECT_EQ(completeArgs(tune, {}, "", {}), (V{"evals=", "list", "plant=", "ref=", "speed="}));
  EXPECT_EQ(completeArgs(tune, {"evals=20"}, "r", {}), (V{"ref="}));
  EXPECT_EQ(completeArgs(tune, {}, "ref=c", {}), (V{"ref=circle"}));
  EXPECT_TRUE(completeArgs(tune, {}, "speed=", {}).empty());
}
