#include "ssl_formation/simulation/playbook.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace ssl_formation::simulation {

namespace {

// The longest a step may be held: a play is a sequence of moves, not a stoppage.
constexpr double kLongestHoldS = 60.0;

// One line's words; a word in double quotes may hold spaces.
struct Words {
  std::vector<std::string> words;
  std::string error;
};

Words split_words(std::string_view line) {
  Words out;
  std::size_t i = 0;
  while (i < line.size()) {
    if (line[i] == ' ' || line[i] == '\t' || line[i] == '\r') {
      ++i;
      continue;
    }
    if (line[i] == '#') break;
    if (line[i] == '"') {
      const std::size_t end = line.find('"', i + 1);
      if (end == std::string_view::npos) {
        out.error = "a name in quotes has no closing quote";
        return out;
      }
      out.words.emplace_back(line.substr(i + 1, end - i - 1));
      i = end + 1;
      continue;
    }
    std::size_t end = i;
    while (end < line.size() && line[end] != ' ' && line[end] != '\t' && line[end] != '\r' &&
           line[end] != '#') {
      ++end;
    }
    out.words.emplace_back(line.substr(i, end - i));
    i = end;
  }
  return out;
}

std::optional<double> number(const std::string& word) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
  if (error != std::errc() || end != word.data() + word.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

std::optional<std::uint32_t> robot_id(const std::string& word) {
  std::uint32_t value = 0;
  const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
  if (error != std::errc() || end != word.data() + word.size()) return std::nullopt;
  return value;
}

class PlaybookParser {
 public:
  explicit PlaybookParser(std::string_view source) : source_(source) {}

  Result<Playbook> parse(std::string_view text) {
    std::istringstream lines{std::string(text)};
    std::string line;
    while (std::getline(lines, line)) {
      ++line_;
      Words words = split_words(line);
      if (!words.error.empty()) return failure(words.error);
      if (words.words.empty()) continue;
      if (std::string problem = take(words.words); !problem.empty()) return failure(problem);
    }
    if (std::string problem = finish_play(); !problem.empty()) return failure(problem);
    if (playbook_.plays.empty()) {
      return fail(std::string(source_) + ": no plays: a playbook needs at least one");
    }
    return std::move(playbook_);
  }

 private:
  Unexpected<Error> failure(const std::string& problem) const {
    return fail(std::string(source_) + ":" + std::to_string(line_) + ": " + problem);
  }

  // Takes one line's words; returns what is wrong with them, or nothing.
  std::string take(const std::vector<std::string>& w) {
    const std::string& keyword = w[0];
    if (keyword == "playbook") {
      if (named_ || play_ || !playbook_.plays.empty()) {
        return "'playbook' names the playbook once, first";
      }
      if (w.size() != 2 || w[1].empty()) return "expected: playbook \"NAME\"";
      playbook_.name = w[1];
      named_ = true;
      return {};
    }
    if (keyword == "play") return start_play(w);
    if (keyword == "restart") {
      if (!play_) return "'restart' belongs to a play: start one with 'play \"NAME\"'";
      if (!play_->steps.empty()) return "'restart' comes before the play's first step";
      if (w.size() != 2) return "expected: restart kickoff|free_kick|any";
      if (w[1] == "kickoff") {
        play_->restart = PlayRestart::kickoff;
      } else if (w[1] == "free_kick") {
        play_->restart = PlayRestart::free_kick;
      } else if (w[1] == "any") {
        play_->restart = PlayRestart::any;
      } else {
        return "restart '" + w[1] + "': expected kickoff, free_kick or any";
      }
      return {};
    }
    if (keyword == "step") return start_step(w);
    if (robot_id(keyword)) return add_target(w);
    return "unknown word '" + keyword + "': expected playbook, play, restart, step or a robot id";
  }

  std::string start_play(const std::vector<std::string>& w) {
    if (std::string problem = finish_play(); !problem.empty()) return problem;
    if (w.size() < 2 || w[1].empty()) return "expected: play \"NAME\" [weight W]";
    Play play;
    play.name = w[1];
    play.line = line_;
    if (w.size() == 4 && w[2] == "weight") {
      const auto weight = number(w[3]);
      if (!weight || !(*weight > 0.0)) return "weight '" + w[3] + "': expected a positive number";
      play.weight = *weight;
    } else if (w.size() != 2) {
      return "expected: play \"NAME\" [weight W] (names with spaces go in quotes)";
    }
    for (const Play& other : playbook_.plays) {
      if (other.name == play.name) {
        return "a second play named '" + play.name + "' (the first is on line " +
               std::to_string(other.line) + ")";
      }
    }
    play_ = std::move(play);
    return {};
  }

  std::string finish_play() {
    if (!play_) return {};
    if (play_->steps.empty()) {
      return "play '" + play_->name + "' (line " + std::to_string(play_->line) + ") has no steps";
    }
    playbook_.plays.push_back(std::move(*play_));
    play_.reset();
    return {};
  }

  std::string start_step(const std::vector<std::string>& w) {
    if (!play_) return "'step' belongs to a play: start one with 'play \"NAME\"'";
    PlayStep step;
    step.line = line_;
    if (w.size() < 2) return "expected: step SECONDS [ball ROBOT|ball goal]";
    const auto hold = number(w[1]);
    if (!hold || !(*hold > 0.0) || *hold > kLongestHoldS) {
      return "step '" + w[1] + "': the seconds to hold it must be more than 0 and at most 60";
    }
    step.hold_s = *hold;
    if (w.size() == 4 && w[2] == "ball") {
      if (w[3] == "goal") {
        step.shot = true;
      } else {
        const auto id = robot_id(w[3]);
        if (!id || *id == 0 || *id > playbook_max_robot_id) {
          return "ball '" + w[3] + "': expected a robot id from 1 to 10 (0 keeps goal), or goal";
        }
        step.ball_robot = *id;
      }
    } else if (w.size() != 2) {
      return "expected: step SECONDS [ball ROBOT|ball goal]";
    }
    play_->steps.push_back(std::move(step));
    return {};
  }

  std::string add_target(const std::vector<std::string>& w) {
    if (!play_ || play_->steps.empty()) return "a robot's target belongs to a step";
    if (w.size() != 3) return "expected: ROBOT X Y";
    const std::uint32_t id = *robot_id(w[0]);
    if (id == 0) return "robot 0 keeps goal: the simulation keeps it on its line";
    if (id > playbook_max_robot_id) {
      return "robot " + w[0] + ": ids go from 1 to 10 (0 keeps goal)";
    }
    const auto x = number(w[1]);
    const auto y = number(w[2]);
    if (!x || !y) return "robot " + w[0] + ": '" + w[1] + " " + w[2] + "' is not two numbers";
    if (std::abs(*x) > 1.0 || std::abs(*y) > 1.0) {
      return "robot " + w[0] + " at " + w[1] + " " + w[2] +
             ": off the field (x and y go from -1 to 1)";
    }
    PlayStep& step = play_->steps.back();
    for (const PlayTarget& target : step.targets) {
      if (target.robot_id == id) return "robot " + w[0] + " twice in one step";
    }
    step.targets.push_back({id, Point{*x, *y}});
    return {};
  }

  std::string_view source_;
  int line_ = 0;
  bool named_ = false;
  Playbook playbook_;
  std::optional<Play> play_;
};

}  // namespace

Result<Playbook> parse_playbook(std::string_view text, std::string_view source) {
  return PlaybookParser(source).parse(text);
}

Result<Playbook> load_playbook(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return fail(path + ": cannot open the playbook");
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) return fail(path + ": cannot read the playbook");
  return parse_playbook(text.str(), path);
}

Result<Playbook> builtin_or_file_playbook(const std::string& name_or_path) {
  if (const auto text = builtin_playbook_text(name_or_path)) {
    return parse_playbook(*text, name_or_path);
  }
  return load_playbook(name_or_path);
}

}  // namespace ssl_formation::simulation
