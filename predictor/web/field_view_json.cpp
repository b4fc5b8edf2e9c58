#include "field_view_json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string_view>

namespace ssl_formation::predictor::web {

namespace {

// A minimal JSON writer: the messages are flat and small, and their strings are our own.
class Json {
 public:
  explicit Json(std::size_t reserve) { out_.reserve(reserve); }

  Json& open(char bracket) {
    comma();
    out_ += bracket;
    first_ = true;
    return *this;
  }
  Json& close(char bracket) {
    out_ += bracket;
    first_ = false;
    return *this;
  }
  Json& key(std::string_view name) {
    comma();
    string_value(name);
    out_ += ':';
    first_ = true;  // the value follows without a comma
    return *this;
  }
  Json& number(double value) {
    comma();
    if (!std::isfinite(value)) {
      out_ += "null";
      return *this;
    }
    if (value == 0.0) value = 0.0;  // no "-0" from the rotation of a centre cell
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", value);
    out_ += text;
    return *this;
  }
  Json& integer(std::uint64_t value) {
    comma();
    out_ += std::to_string(value);
    return *this;
  }
  Json& signed_integer(std::int64_t value) {
    comma();
    out_ += std::to_string(value);
    return *this;
  }
  Json& boolean(bool value) {
    comma();
    out_ += value ? "true" : "false";
    return *this;
  }
  Json& null() {
    comma();
    out_ += "null";
    return *this;
  }
  Json& string(std::string_view value) {
    comma();
    string_value(value);
    return *this;
  }
  Json& pair(double x, double y) {
    open('[').number(x).number(y);
    return close(']');
  }
  std::string take() { return std::move(out_); }

 private:
  void comma() {
    if (!first_) out_ += ',';
    first_ = false;
  }
  void string_value(std::string_view value) {
    out_ += '"';
    for (const char c : value) {
      if (c == '"' || c == '\\') {
        out_ += '\\';
        out_ += c;
      } else if (static_cast<unsigned char>(c) < 0x20) {
        char escaped[8];
        std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(c));
        out_ += escaped;
      } else {
        out_ += c;
      }
    }
    out_ += '"';
  }

  std::string out_;
  bool first_ = true;
};

void write_setup(Json& json, const FieldViewSetup& setup) {
  json.key("field").open('{').key("length").number(setup.field.length_mm);
  json.key("width").number(setup.field.width_mm);
  const ViewMarkings& m = setup.markings;
  json.key("markings").open('{').key("goal_width").number(m.goal_width_mm);
  json.key("goal_depth").number(m.goal_depth_mm).key("boundary_width").number(m.boundary_width_mm);
  json.key("penalty_area_depth").number(m.penalty_area_depth_mm);
  json.key("penalty_area_width").number(m.penalty_area_width_mm);
  json.key("center_circle_radius").number(m.center_circle_radius_mm);
  json.key("source").string(m.source).close('}').close('}');
  json.key("grid").open('{').key("length").integer(static_cast<std::uint64_t>(setup.grid.length()));
  json.key("width").integer(static_cast<std::uint64_t>(setup.grid.width())).close('}');
  json.key("opponent_color").string(to_string(setup.opponent_color));
  json.key("our_color").string(to_string(opposite(setup.opponent_color)));
  json.key("opponent_attacks").string(to_string(setup.opponent_attacks));
}

void write_ours(Json& json, std::span<const TeamRobot> ours) {
  json.key("ours").open('[');
  for (const TeamRobot& robot : ours) {
    json.open('{')
        .key("id")
        .integer(robot.robot_id)
        .key("x")
        .number(robot.x)
        .key("y")
        .number(robot.y);
    json.close('}');
  }
  json.close(']');
}

// The ball where it is and its path, in feed coordinates; null when it is not seen lately.
void write_ball(Json& json, const BallTrail* ball) {
  json.key("ball");
  const std::optional<Point> at = ball ? ball->position() : std::nullopt;
  if (!at) {
    json.null();
    return;
  }
  json.open('{').key("x").number(at->x).key("y").number(at->y).key("path").open('[');
  for (const Point& p : ball->path()) json.pair(p.x, p.y);
  json.close(']').close('}');
}

void write_horizons(Json& json, const std::vector<LiveScore::Horizon>& horizons) {
  json.open('[');
  for (const LiveScore::Horizon& h : horizons) {
    if (h.robots <= 0.0) continue;
    json.open('{').key("horizon_s").number(h.horizon_s).key("model_mm").number(h.model_mm);
    json.key("persistence_mm").number(h.persistence_mm).key("robots").number(h.robots).close('}');
  }
  json.close(']');
}

// Whose restart, placement or timeout the referee's command is, as the opponent followed sees
// it; none for commands of neither team (HALT, STOP, the starts).
void write_match(Json& json, const FieldViewStatus& status) {
  const RefereeView& view = status.referee_view;
  json.key("match").open('{').key("opponent").string(status.opponent);
  json.key("game_state").string(status.game_state).key("phase").string(to_string(status.phase));
  json.key("referee").string(status.referee);
  json.key("heard").boolean(status.referee_heard);
  json.key("stage");
  if (const std::string stage = stage_name(view.stage); status.referee_heard && !stage.empty()) {
    json.string(stage);
  } else {
    json.null();
  }
  json.key("for_team");
  const std::optional<TeamColor> team =
      status.referee_heard ? team_of_command(view.command) : std::nullopt;
  if (team) {
    json.string(*team == status.setup.opponent_color ? "opponent" : "us");
  } else {
    json.null();
  }
  json.key("yellow").string(view.yellow_name).key("blue").string(view.blue_name);
  json.key("designated_position");
  if (status.referee_heard && view.designated_position) {
    json.pair(view.designated_position->x, view.designated_position->y);
  } else {
    json.null();
  }
  json.close('}');
}

// A grid cell as [x, y] and its centre in the feed's coordinates.
void write_cell(Json& json, const proto::GridCell& cell, const FieldViewSetup& setup) {
  const Cell c{static_cast<int>(cell.x()), static_cast<int>(cell.y())};
  json.open('{').key("cell").pair(c.x, c.y);
  if (setup.grid.contains(c)) {
    const Point centre = normalise(setup.grid.centre_of(c, setup.field), setup.opponent_attacks);
    json.key("centre").pair(centre.x, centre.y);
  } else {
    json.key("centre").null();
  }
  json.close('}');
}

}  // namespace

std::string prediction_json(const proto::FormationPrediction& message, const FieldViewSetup& setup,
                            std::span<const TeamRobot> ours, const BallTrail& ball) {
  Json json(1024 + 160 * static_cast<std::size_t>(message.robots_size()) *
                       (1 + static_cast<std::size_t>(message.steps_size())));
  json.open('{').key("type").string("prediction");
  json.key("frame").integer(message.frame_number()).key("t").number(message.t_capture());
  write_setup(json, setup);
  json.key("model").string(message.has_model() ? message.model() : std::string("paper"));
  json.key("table_transitions").integer(message.table_transitions());
  json.key("step_seconds").number(message.step_seconds());
  json.key("centroid");
  write_cell(json, message.centroid_cell(), setup);
  json.key("opponent").open('[');
  for (const proto::CurrentRobot& robot : message.robots()) {
    json.open('{').key("id").integer(robot.robot_id());
    json.key("x").number(robot.position().x()).key("y").number(robot.position().y());
    json.key("cell").pair(robot.position_cell().x(), robot.position_cell().y()).close('}');
  }
  json.close(']');
  write_ours(json, ours);
  write_ball(json, &ball);
  json.key("steps").open('[');
  for (const proto::PredictedStep& step : message.steps()) {
    json.open('{').key("step").integer(step.step());
    json.key("horizon_s")
        .number(step.has_horizon_seconds()
                    ? step.horizon_seconds()
                    : static_cast<double>(step.step()) * message.step_seconds());
    json.key("centroid");
    write_cell(json, step.centroid_cell(), setup);
    json.key("centroid_p").number(step.centroid_probability());
    json.key("centroid_unseen").boolean(step.centroid_unseen());
    json.key("formation_p").number(step.formation_probability());
    json.key("confidence").number(step.confidence());
    json.key("robots").open('[');
    for (const proto::PredictedRobot& robot : step.robots()) {
      json.open('{').key("id").integer(robot.robot_id());
      json.key("cell").pair(robot.position_cell().x(), robot.position_cell().y());
      json.key("centre").pair(robot.cell_centre().x(), robot.cell_centre().y());
      json.key("p").number(robot.probability()).key("unseen").boolean(robot.unseen());
      if (robot.has_position()) {
        json.key("position").pair(robot.position().x(), robot.position().y());
        json.key("radius_50_mm").number(robot.radius_50_mm());
        json.key("radius_90_mm").number(robot.radius_90_mm());
      }
      json.close('}');
    }
    json.close(']').close('}');
  }
  json.close(']').close('}');
  return json.take();
}

std::string status_json(const FieldViewStatus& status) {
  Json json(512 + 64 * status.ours.size());
  json.open('{').key("type").string("status");
  write_setup(json, status.setup);
  json.key("packets").integer(status.packets).key("packets_per_s").number(status.packets_per_s);
  json.key("since_packet_s");
  if (status.since_packet_s) {
    // A clock read racing the packet's own may come out a hair below 0: never say so.
    json.number(std::max(0.0, *status.since_packet_s));
  } else {
    json.null();
  }
  json.key("last_packet_unix_ms");
  if (status.last_packet_unix_ms) {
    json.signed_integer(*status.last_packet_unix_ms);
  } else {
    json.null();
  }
  json.key("server_unix_ms");
  if (status.server_unix_ms) {
    json.signed_integer(*status.server_unix_ms);
  } else {
    json.null();
  }
  json.key("parse_errors")
      .integer(status.parse_errors)
      .key("kernel_drops")
      .integer(status.kernel_drops);
  json.key("formations").integer(status.formations).key("predictions").integer(status.predictions);
  json.key("table").open('{').key("loaded").boolean(status.table_loaded);
  json.key("transitions").integer(status.table_transitions);
  json.key("formations").integer(status.table_formations);
  json.key("motion_instances");
  if (status.table_motion_instances) {
    json.integer(*status.table_motion_instances);
  } else {
    json.null();
  }
  json.key("states_seen").integer(status.table_states_seen);
  json.key("reloads").integer(status.table_reloads);
  json.key("loaded_unix_ms");
  if (status.table_loaded_unix_ms) {
    json.integer(static_cast<std::uint64_t>(*status.table_loaded_unix_ms));
  } else {
    json.null();
  }
  json.key("error").string(status.table_error).close('}');
  json.key("clients").integer(status.clients).key("dropped_frames").integer(status.dropped_frames);
  write_ours(json, status.ours);
  write_ball(json, status.ball);
  write_match(json, status);
  json.key("live_score");
  write_horizons(json, status.live_score);
  json.key("live_score_by_phase").open('[');
  for (const PhaseLiveScore& phase : status.live_score_by_phase) {
    json.open('{').key("phase").string(to_string(phase.phase)).key("horizons");
    write_horizons(json, phase.horizons);
    json.close('}');
  }
  json.close(']');
  json.close('}');
  return json.take();
}

}  // namespace ssl_formation::predictor::web
