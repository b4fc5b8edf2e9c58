#include "ssl_formation/sampler.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {

namespace {
constexpr double time_epsilon_s = 1e-9;
// Beyond this many steps from the anchor the clock is treated as restarted, which also keeps
// the instant number far from int64 overflow whatever t_capture a packet claims.
constexpr double max_instant_number = 1e12;
}  // namespace

FormationSampler::FormationSampler(SamplerConfig config, SampleHandler on_sample)
    : config_(config),
      codec_(config.grid),
      on_sample_(std::move(on_sample)),
      field_(config.field) {
  if (!std::isfinite(config_.step_s) || config_.step_s <= 0.0) {
    throw std::invalid_argument("step must be a positive number of seconds");
  }
  if (!field_.valid()) {
    throw std::invalid_argument("field length and width must be positive");
  }
  observations_.resize(std::size_t{config_.max_robot_id} + 1);
}

void FormationSampler::add(const SSL_WrapperPacket& packet) {
  ++counters_.packets;
  if (packet.has_geometry()) add_geometry(packet.geometry());
  if (packet.has_detection()) add_detection(packet.detection());
}

void FormationSampler::add_geometry(const SSL_GeometryData& geometry) {
  ++counters_.geometry_packets;
  if (!config_.use_geometry) return;
  const FieldSize field{static_cast<double>(geometry.field().field_length()),
                        static_cast<double>(geometry.field().field_width())};
  if (!field.valid()) {
    ++counters_.geometry_invalid;
    return;
  }
  if (field == field_) return;
  field_ = field;
  ++counters_.field_changes;
  // Cells of the old and the new field do not compare: no transition spans the change.
  if (previous_) {
    previous_.reset();
    ++counters_.chain_breaks;
  }
}

void FormationSampler::add_detection(const SSL_DetectionFrame& frame) {
  ++counters_.detection_frames;
  const double t = frame.t_capture();
  if (!std::isfinite(t)) {
    ++counters_.frames_bad_time;
    return;
  }
  if (frame.camera_id() > config_.max_camera_id) {
    ++counters_.frames_bad_camera;
    return;
  }
  const auto& robots = config_.opponent_color == TeamColor::yellow ? frame.robots_yellow()
                                                                   : frame.robots_blue();
  if (static_cast<std::uint32_t>(robots.size()) > config_.max_robots_per_frame) {
    ++counters_.frames_too_many_robots;
    return;
  }

  frame_scratch_.clear();
  for (const SSL_DetectionRobot& robot : robots) {
    if (!robot.has_robot_id() || robot.robot_id() > config_.max_robot_id) {
      ++counters_.robots_bad_id;
      continue;
    }
    const double x = robot.x();
    const double y = robot.y();
    if (!std::isfinite(x) || !std::isfinite(y)) {
      ++counters_.robots_non_finite;
      continue;
    }
    if (std::abs(x) > config_.max_abs_coordinate_mm || std::abs(y) > config_.max_abs_coordinate_mm) {
      ++counters_.robots_out_of_range;
      continue;
    }
    // One camera may report two blobs with the same id: keep the more confident one.
    const auto same = std::find_if(frame_scratch_.begin(), frame_scratch_.end(),
                                   [&](const Detection& d) { return d.robot_id == robot.robot_id(); });
    if (same != frame_scratch_.end()) {
      ++counters_.robots_duplicate_in_frame;
      if (robot.confidence() > same->confidence) *same = {robot.robot_id(), x, y, robot.confidence()};
      continue;
    }
    frame_scratch_.push_back({robot.robot_id(), x, y, robot.confidence()});
  }
  counters_.robots_accepted += frame_scratch_.size();
  if (frame_scratch_.empty()) ++counters_.frames_without_opponent;

  const double clock_reset_s = config_.clock_reset_s > 0.0 ? config_.clock_reset_s : 2.0 * config_.step_s;
  if (anchored_ && t < newest_s_ - clock_reset_s) {
    ++counters_.clock_resets;
    restart();
  }
  if (!anchored_) {
    anchored_ = true;
    anchor_s_ = t;
    newest_s_ = t;
    next_k_ = 0;
  }
  double instant_number = std::floor((t - anchor_s_) / config_.step_s + time_epsilon_s);
  if (std::abs(instant_number) > max_instant_number) {
    ++counters_.clock_resets;
    restart();
    anchored_ = true;
    anchor_s_ = t;
    newest_s_ = t;
    instant_number = 0.0;
  }
  const auto k = static_cast<std::int64_t>(instant_number);

  if (k < next_k_) {
    // Between two sample instants (the normal case at 60 Hz), unless older than the last sample.
    if (next_k_ > 0 && t < instant(next_k_ - 1) - time_epsilon_s) {
      ++counters_.frames_late;
      return;
    }
  } else {
    // This frame reaches a new instant. If an earlier one is still waiting for a camera that
    // never delivered (a dropped frame), hand it on now, before the new data overwrites it.
    if (open_k_ && k > *open_k_) emit(*open_k_, *open_k_ != 0);
    if (!open_k_ || k > *open_k_) open_k_ = k;
  }

  apply_detections(frame.camera_id(), t);
  last_frame_number_ = frame.frame_number();
  newest_s_ = std::max(newest_s_, t);
  if (open_k_ && instant_complete(*open_k_)) emit(*open_k_, false);
}

void FormationSampler::apply_detections(std::uint32_t camera_id, double time_s) {
  auto camera = std::find_if(camera_last_.begin(), camera_last_.end(),
                             [&](const auto& entry) { return entry.first == camera_id; });
  if (camera == camera_last_.end()) {
    camera_last_.emplace_back(camera_id, time_s);
  } else {
    camera->second = std::max(camera->second, time_s);
  }

  for (const Detection& d : frame_scratch_) {
    Observation& obs = observations_[d.robot_id];
    if (!obs.seen) {
      observed_ids_.insert(std::upper_bound(observed_ids_.begin(), observed_ids_.end(), d.robot_id),
                           d.robot_id);
      obs = Observation{time_s, d.x, d.y, 1.0, camera_id, true};
    } else if (time_s > obs.time_s + config_.same_instant_s ||
               (std::abs(time_s - obs.time_s) <= config_.same_instant_s &&
                camera_id == obs.camera_id)) {
      obs = Observation{time_s, d.x, d.y, 1.0, camera_id, true};
    } else if (std::abs(time_s - obs.time_s) <= config_.same_instant_s) {
      // Overlapping cameras saw the same robot at the same instant: one robot, averaged.
      obs.sum_x += d.x;
      obs.sum_y += d.y;
      obs.weight += 1.0;
      obs.time_s = std::max(obs.time_s, time_s);
    }
    // Older than what we have: an out-of-order frame, ignored for this robot.
  }
}

bool FormationSampler::instant_complete(std::int64_t k) const {
  const double sample_s = instant(k);
  // The first instant waits a little so that every camera has a chance to be discovered;
  // otherwise the first sample would hold only the first camera's robots.
  if (k == 0 && newest_s_ < anchor_s_ + std::min(config_.camera_timeout_s, config_.step_s)) {
    return false;
  }
  const double live_window = std::max(config_.camera_timeout_s, 1.5 * config_.step_s);
  for (const auto& [camera_id, last_s] : camera_last_) {
    if (last_s >= newest_s_ - live_window && last_s < sample_s - time_epsilon_s) return false;
  }
  return true;
}

Formation FormationSampler::build_formation(const StateCodec& codec, const FieldSize& field,
                                            std::vector<FormationRobot> robots,
                                            const Formation* previous) {
  Formation formation;
  std::sort(robots.begin(), robots.end(),
            [](const FormationRobot& a, const FormationRobot& b) { return a.robot_id < b.robot_id; });
  if (!robots.empty()) {
    double sum_x = 0.0;
    double sum_y = 0.0;
    for (const FormationRobot& robot : robots) {
      sum_x += robot.position.x;
      sum_y += robot.position.y;
    }
    const double n = static_cast<double>(robots.size());
    formation.centroid = Point{sum_x / n, sum_y / n};
  }
  const Grid& grid = codec.grid();
  formation.centroid_cell = grid.cell_of(formation.centroid, field);
  formation.continues_previous = previous != nullptr;
  for (FormationRobot& robot : robots) {
    robot.cell = grid.cell_of(robot.position, field);
    const FormationRobot* before = previous ? previous->find(robot.robot_id) : nullptr;
    robot.previous_cell = before ? before->cell : robot.cell;
    robot.state = codec.encode(RobotState{formation.centroid_cell, robot.cell, robot.previous_cell});
  }
  formation.robots = std::move(robots);
  return formation;
}

void FormationSampler::emit(std::int64_t k, bool forced) {
  const double sample_s = instant(k);
  next_k_ = k + 1;
  open_k_.reset();

  const double fresh_s = std::min(config_.robot_timeout_s, config_.step_s);
  std::vector<FormationRobot> robots;
  robots.reserve(observed_ids_.size());
  for (const std::uint32_t id : observed_ids_) {
    const Observation& obs = observations_[id];
    if (obs.time_s <= sample_s - fresh_s + time_epsilon_s) continue;
    FormationRobot robot;
    robot.robot_id = id;
    robot.feed_position = Point{obs.sum_x / obs.weight, obs.sum_y / obs.weight};
    robot.position = normalise(robot.feed_position, config_.opponent_attacks);
    robots.push_back(robot);
  }
  if (robots.empty()) {
    ++counters_.samples_empty;
    if (previous_) {
      previous_.reset();
      ++counters_.chain_breaks;
    }
    return;
  }

  const bool continues = previous_ && k - previous_k_ == 1;
  if (previous_ && !continues) ++counters_.chain_breaks;
  FormationSample& sample = sample_scratch_;
  sample.formation =
      build_formation(codec_, field_, std::move(robots), continues ? &*previous_ : nullptr);
  sample.formation.time_s = sample_s;
  sample.formation.frame_number = last_frame_number_;
  sample.transitions.clear();
  if (continues) {
    for (const FormationRobot& robot : sample.formation.robots) {
      if (const FormationRobot* before = previous_->find(robot.robot_id)) {
        sample.transitions.push_back({robot.robot_id, before->state, robot.state});
      }
    }
  }
  ++counters_.samples;
  if (forced) ++counters_.samples_forced;
  counters_.transitions += sample.transitions.size();
  previous_ = sample.formation;
  previous_k_ = k;
  if (on_sample_) on_sample_(sample);
}

void FormationSampler::restart() {
  if (previous_) ++counters_.chain_breaks;
  previous_.reset();
  anchored_ = false;
  open_k_.reset();
  next_k_ = 0;
  camera_last_.clear();
  for (const std::uint32_t id : observed_ids_) observations_[id].seen = false;
  observed_ids_.clear();
}

}  // namespace ssl_formation
