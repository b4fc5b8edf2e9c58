#pragma once
// Official logs of a match as a recorder keeps it: vision frames at 60 Hz and the game
// controller's referee messages at 10 Hz in between, each stretch of the match scripted by the
// test (who plays which colour on which side, the command, when the vision pauses).

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_gc_referee_message.pb.h"

namespace ssl_formation::testing {

struct RefereeSpec {
  Referee::Command command = Referee::NORMAL_START;
  std::uint32_t command_counter = 1;
  std::string yellow;
  std::string blue;
  std::optional<bool> blue_on_positive_half;
  std::string source = "test-game-controller";
  Referee::Stage stage = Referee::NORMAL_FIRST_HALF;
  std::optional<Point> designated_position;  // mm, feed coordinates (a ball placement's target)
};

// The message's bytes, as the game controller sends them.
inline std::string referee_payload(const RefereeSpec& spec, double sent_s = 0.0) {
  Referee message;
  message.set_packet_timestamp(static_cast<std::uint64_t>(std::llround(sent_s * 1e6)));
  message.set_stage(spec.stage);
  message.set_command(spec.command);
  message.set_command_counter(spec.command_counter);
  message.set_command_timestamp(0);
  for (auto [team, name] : {std::pair{message.mutable_yellow(), &spec.yellow},
                            std::pair{message.mutable_blue(), &spec.blue}}) {
    team->set_name(*name);
    team->set_score(0);
    team->set_red_cards(0);
    team->set_yellow_cards(0);
    team->set_timeouts(4);
    team->set_timeout_time(300000000);
    team->set_goalkeeper(0);
  }
  if (spec.blue_on_positive_half) {
    message.set_blue_team_on_positive_half(*spec.blue_on_positive_half);
  }
  if (!spec.source.empty()) message.set_source_identifier(spec.source);
  if (spec.designated_position) {
    message.mutable_designated_position()->set_x(static_cast<float>(spec.designated_position->x));
    message.mutable_designated_position()->set_y(static_cast<float>(spec.designated_position->y));
  }
  return message.SerializeAsString();
}

struct MatchScript {
  double start_s = 100.0;  // t_capture (and receive time) of the first tick
  double seconds = 60.0;
  // The frame at `t` seconds into the match (frame_number and t_capture are set by the writer);
  // none: the vision sends nothing then.
  std::function<std::optional<DetectionFrameSpec>(double t)> frame;
  // The referee's message at `t`; none: it sends nothing then. Null: a log without a referee.
  std::function<std::optional<RefereeSpec>(double t)> referee;
};

// Writes the script as an official log (.log, or gzip with .log.gz): a geometry packet (a 9 x 6 m
// field), then every 1/60 s a frame, preceded every sixth tick by the referee's message. Returns
// an error message, empty on success.
inline std::string write_match_log(const std::filesystem::path& path, const MatchScript& script) {
  auto writer = LogWriter::create(path);
  if (!writer) return writer.error().message;
  const auto ns = [](double t) { return static_cast<std::int64_t>(std::llround(t * 1e9)); };
  if (!writer->write_vision(make_geometry_packet(FieldSize{9000.0, 6000.0}), ns(script.start_s))) {
    return writer->error();
  }
  const auto ticks = static_cast<int>(std::lround(script.seconds * 60.0));
  std::uint32_t frame_number = 0;
  for (int tick = 0; tick < ticks; ++tick) {
    const double t = tick / 60.0;
    const double now_s = script.start_s + t;
    if (script.referee && tick % 6 == 0) {
      if (const std::optional<RefereeSpec> spec = script.referee(t)) {
        if (!writer->write(static_cast<std::int32_t>(LogMessageType::referee), ns(now_s),
                           referee_payload(*spec, now_s))) {
          return writer->error();
        }
      }
    }
    if (std::optional<DetectionFrameSpec> frame = script.frame(t)) {
      frame->frame_number = frame_number++;
      frame->t_capture = now_s;
      if (!writer->write_vision(make_detection_packet(*frame), ns(now_s))) return writer->error();
    }
  }
  if (!writer->close()) return writer->error();
  return {};
}

}  // namespace ssl_formation::testing
