#include "pc_server/terminal/interactive_console.hpp"

#include <iostream>

#include "pc_server/terminal/key_decoder.hpp"
#include "pc_server/terminal/keyboard_teleop.hpp"
#include "pc_server/console/status_line.hpp"
#include "shared/util/clock.hpp"

namespace inspect::server {

namespace {
constexpr const char* kPrompt = "> ";
constexpr int kPollMs = 20;
// A lone ESC is a key only if no sequence bytes follow within this time.
constexpr double kEscTimeoutS = 0.05;

double nowS() { return static_cast<double>(monoNowNs()) * 1e-9; }
}  // namespace

InteractiveConsole::InteractiveConsole(Console& console, StopFlag& stop, double status_refresh_hz)
    : console_(console),
      stop_(stop),
      term_(0, 1),
      reader_(0, stop),
      editor_(kPrompt, [&console](const std::string& before) { return console.completions(before); }),
      status_period_(std::chrono::nanoseconds(static_cast<int64_t>(1e9 / status_refresh_hz))) {}

std::string InteractiveConsole::statusText() const {
  const std::string& robot = console_.selected();
  const int n = console_.registry().connectedCount();
  if (robot.empty()) return "no robot selected | " + std::to_string(n) + " connected | type 'help'";
  return console_.statusText(robot);
}

void InteractiveConsole::refreshStatus(bool force) {
  if (!term_.isTty()) return;
  const auto now = std::chrono::steady_clock::now();
  if (!force && now < next_status_) return;
  next_status_ = now + status_period_;
  const std::string& robot = console_.selected();
  const bool alarm = !robot.empty() && statusIsAlarm(console_.registry().snapshot(robot, monoNowNs()));
  term_.drawStatus(statusText(), alarm);
}

void InteractiveConsole::printAbove(const std::string& text) {
  if (text.empty()) return;
  std::cout << "\r\x1b[K" << text << (term_.rawMode() ? editor_.render() : std::string(kPrompt));
  std::cout.flush();
}

LineReader::Result InteractiveConsole::nextLine(std::string& line) {
  if (!term_.rawMode()) return reader_.nextLine(line, kPollMs);
  if (pending_.empty()) {
    const auto r = reader_.readChunk(pending_, kPollMs);
    if (r != LineReader::Result::kData) return r;
  }
  // Feed up to the end of a line; the rest (a pasted second line) waits for the next call.
  std::size_t used = 0;
  auto outcome = LineEditor::Outcome::kEditing;
  while (used < pending_.size() && outcome == LineEditor::Outcome::kEditing) outcome = editor_.feed(pending_[used++]);
  pending_.erase(0, used);
  std::cout << editor_.takeOutput();
  std::cout.flush();
  if (outcome == LineEditor::Outcome::kEof) return LineReader::Result::kEof;
  if (outcome != LineEditor::Outcome::kLine) return LineReader::Result::kTimeout;
  line = editor_.takeLine();
  return LineReader::Result::kData;
}

void InteractiveConsole::run() {
  const bool tty = term_.isTty();
  if (tty) {
    console_.setTeleopHandler([this](TeleopMode m, const std::string& r) { return teleop(m, r); });
    term_.enableStatusLine();
    term_.enterRawMode();  // keys to the line editor
    console_.setAlarmStyle(true);
  }
  console_.setIdleHook([this] { refreshStatus(false); });
  std::cout << "pc_server console: 'help' lists the commands, 'quit' leaves\n" << kPrompt;
  std::cout.flush();
  refreshStatus(true);
  int line_no = 0;
  while (!console_.quitRequested()) {
    std::string line;
    const auto r = nextLine(line);
    if (r == LineReader::Result::kStopped) break;
    if (r == LineReader::Result::kEof) {
      std::cout << "\n";
      break;
    }
    if (r == LineReader::Result::kData) {
      console_.execute(line, ++line_no);
      if (console_.quitRequested()) break;
      std::cout << (tty ? editor_.render() : std::string(kPrompt));
      std::cout.flush();
    } else {
      printAbove(console_.background());
    }
    refreshStatus(false);
  }
  console_.setIdleHook(nullptr);
  console_.setTeleopHandler(nullptr);
  std::cout.flush();
  // term_ restores the scroll region and the terminal mode when destroyed.
}

bool InteractiveConsole::teleop(TeleopMode mode, const std::string& robot_id) {
  const auto& opt = console_.options();
  KeyboardTeleop::Params params;
  params.max_v_m_s = opt.max_v_m_s;
  params.max_w_rad_s = opt.max_w_rad_s;
  KeyboardTeleop kt(mode, params);
  KeyDecoder decoder;
  // Every set-point and the stop go through the operator service: its ranges
  // and the one-controlling-operator rule hold for the keyboard too.
  OperatorService& service = console_.service();
  const uint64_t session = console_.session();
  RobotRegistry& registry = console_.registry();

  std::cout << "teleop " << (mode == TeleopMode::kStep ? "step" : "hold") << " on " << robot_id << ": "
            << (mode == TeleopMode::kStep ? "w/s or Up/Down: v -+0.05 m/s, a/d or Left/Right: w +-0.1 rad/s"
                                                    : "hold w/s/a/d or arrows to drive (release stops)")
            << "; space: zero; q/Esc: leave\n";
  const bool was_raw = term_.rawMode();  // the line editor's mode: given back as found
  term_.enterRawMode();
  term_.showCursor(false);  // while the gauge is shown
  uint64_t last_id = 0;
  std::string note;
  auto gauge = [&] {
    std::string s = "\r\x1b[K" + kt.gauge() + note;
    std::cout << s;
    std::cout.flush();
  };
  auto apply = [&] {
    // Lease 0: the keyboard's own deadman (hold mode) zeroes the set-point.
    const Issued issued = service.teleop(session, robot_id, kt.v(), kt.w(), 0.0, monoNowNs());
    if (const auto* r = std::get_if<CallResult>(&issued)) {
      last_id = 0;
      note = "  (" + r->reason + ")";
    } else {
      last_id = std::get<PendingCall>(issued).command_id;
      note = "";
    }
  };
  gauge();
  bool ok = true;
  double esc_since = 0;
  while (!kt.finished()) {
    std::string bytes;
    const auto r = reader_.readChunk(bytes, kPollMs);
    if (r == LineReader::Result::kStopped || r == LineReader::Result::kEof) break;
    const double t = nowS();
    std::vector<KeyboardTeleop::Key> keys;
    if (r == LineReader::Result::kData) {
      keys = decoder.feed(bytes);
      if (decoder.pending()) esc_since = t;
    } else if (decoder.pending() && t - esc_since > kEscTimeoutS) {
      keys = decoder.flush();
    }
    bool changed = false;
    for (const auto k : keys) changed = kt.onKey(k, t) || changed;
    changed = kt.tick(t) || changed;
    if (changed && !kt.finished()) apply();

    const auto snap = registry.snapshot(robot_id, monoNowNs());
    if (!snap || !snap->connected) {
      std::cout << "\r\x1b[K" << robot_id << " disconnected: leaving teleop\n";
      ok = false;
      break;
    }
    if (last_id != 0) {
      if (const auto a = registry.ack(robot_id, last_id); a && a->status() == v1::Ack::REJECTED) {
        const std::string n = "  (rejected: " + a->reason() + ")";
        if (n != note) {
          note = n;
          changed = true;
        }
      }
    }
    const std::string bg = console_.background();
    if (!bg.empty()) {
      std::cout << "\r\x1b[K" << bg;
      changed = true;
    }
    if (changed || r == LineReader::Result::kData) gauge();
    refreshStatus(false);
  }
  // Leaving teleop zeroes the robot at once (Stop also ends the re-send).
  const bool sent = std::holds_alternative<PendingCall>(service.stop(session, robot_id, monoNowNs()));
  if (!sent) service.clearTeleop(robot_id);
  if (was_raw) term_.showCursor(true);
  else term_.leaveRawMode();
  std::cout << "\r\x1b[K" << "teleop: left" << (sent ? ", stop sent to " + robot_id : "") << "\n";
  std::cout.flush();
  return ok;
}

}  // namespace inspect::server
