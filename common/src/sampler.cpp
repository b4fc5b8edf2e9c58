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
    : config_(config), codec_(config.grid), on_sample_(std::move(on_sample)), field_(config.field) {
  if (!std::isfinite(config_.step_s) || config_.step_s <= 0.0) {
    throw std::invalid_argument("step must be a positive number of seconds");
  }
  if (!field_.valid()) {
    throw std::invalid_argument("field length and width must be positive");
  }
  // The buffers every sample goes through, reserved here, one after the other, so they share a
  // few pages: a daemon waking every 16 ms pays for each page it touches (its TLB and caches
  // are cold by then). A steady stream of up to 16 robots per team then never allocates; a chain
  // break costs one allocation, when the next sample becomes the previous one.
  constexpr std::size_t usual_robots = 16;
  frame_scratch_.reserve(usual_robots);
  observed_ids_.reserve(2 * usual_robots);
  camera_last_.reserve(8);
  robots_scratch_.reserve(usual_robots);
  sample_scratch_.formation.robots.reserve(usual_robots);
  sample_scratch_.transitions.reserve(usual_robots);
  observations_.resize(std::size_t{config_.max_robot_id} + 1);
}

void FormationSampler::add(const SSL_WrapperPacket& packet) {
  to_vision_frame(packet, packet_scratch_);
  add(packet_scratch_);
}

void FormationSampler::add(const VisionFrame& frame) {
  ++counters_.packets;
  if (!frame.has_geometry && !frame.has_detection) ++counters_.packets_empty;
  if (frame.has_geometry) add_geometry(frame.field_length, frame.field_width);
  if (frame.has_detection) add_detection(frame.detection);
}

void FormationSampler::add_geometry(std::int32_t field_length, std::int32_t field_width) {
  ++counters_.geometry_packets;
  if (!config_.use_geometry) return;
  const FieldSize field{static_cast<double>(field_length), static_cast<double>(field_width)};
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

void FormationSampler::add_detection(const VisionDetection& frame) {
  ++counters_.detection_frames;
  const double t = frame.t_capture;
  if (!std::isfinite(t)) {
    ++counters_.frames_bad_time;
    return;
  }
  if (frame.camera_id > config_.max_camera_id) {
    ++counters_.frames_bad_camera;
    return;
  }
  const std::vector<VisionRobot>& robots = frame.robots(config_.opponent_color);
  if (static_cast<std::uint32_t>(robots.size()) > config_.max_robots_per_frame) {
    ++counters_.frames_too_many_robots;
    return;
  }

  frame_scratch_.clear();
  for (const VisionRobot& robot : robots) {
    if (!robot.has_robot_id || robot.robot_id > config_.max_robot_id) {
      ++counters_.robots_bad_id;
      continue;
    }
    const double x = robot.x;
    const double y = robot.y;
    if (!std::isfinite(x) || !std::isfinite(y)) {
      ++counters_.robots_non_finite;
      continue;
    }
    if (std::abs(x) > config_.max_abs_coordinate_mm ||
        std::abs(y) > config_.max_abs_coordinate_mm) {
      ++counters_.robots_out_of_range;
      continue;
    }
    // One camera may report two blobs with the same id: keep the more confident one.
    const auto same =
        std::find_if(frame_scratch_.begin(), frame_scratch_.end(),
                     [&](const Detection& d) { return d.robot_id == robot.robot_id; });
    if (same != frame_scratch_.end()) {
      ++counters_.robots_duplicate_in_frame;
      if (robot.confidence > same->confidence) *same = {robot.robot_id, x, y, robot.confidence};
      continue;
    }
    frame_scratch_.push_back({robot.robot_id, x, y, robot.confidence});
  }
  counters_.robots_accepted += frame_scratch_.size();
  if (frame_scratch_.empty()) ++counters_.frames_without_opponent;
  place_frame(frame.camera_id, frame.frame_number, t);
}

// Decides which clock the frame (its detections in frame_scratch_) belongs to, and uses it.
void FormationSampler::place_frame(std::uint32_t camera_id, std::uint32_t frame_number, double t) {
  const double clock_reset_s =
      config_.clock_reset_s > 0.0 ? config_.clock_reset_s : 2.0 * config_.step_s;
  if (anchored_ && std::abs(t - newest_s_) > clock_reset_s) {
    set_aside(camera_id, frame_number, t);
    return;
  }
  // A restarted clock passes through times near the old one: while its frames are being set
  // aside, a frame that fits it and would be too old for the current clock is its too.
  if (!pending_.empty() && std::abs(t - other_.newest_s) <= clock_reset_s && next_k_ > 0 &&
      t < instant(next_k_ - 1) - time_epsilon_s) {
    set_aside(camera_id, frame_number, t);
    return;
  }
  if (!pending_.empty()) {
    // The current clock goes on after frames of another one: two senders, unless the other
    // clock never advanced (a stray old frame, a duplicate of one).
    if (other_.advancing && !conflict_) {
      conflict_ = true;
      ++counters_.clock_conflicts;
    }
    pending_.clear();
  }
  if (!anchored_) {
    anchored_ = true;
    anchor_s_ = t;
    newest_s_ = t;
    next_k_ = 0;
  }
  const double hold_s =
      config_.clock_conflict_hold_s > 0.0 ? config_.clock_conflict_hold_s : 4.0 * config_.step_s;
  if (other_.active && std::max(newest_s_, t) - other_.seen_at_s > hold_s) {
    other_ = OtherClock{};
    conflict_ = false;
  }

  auto camera = std::find_if(camera_last_.begin(), camera_last_.end(),
                             [&](const CameraClock& c) { return c.camera_id == camera_id; });
  if (camera != camera_last_.end() && camera->last_s == t &&
      camera->last_frame_number == frame_number) {
    ++counters_.frames_duplicate;
    return;
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

  apply_detections(camera_id, t);
  camera = std::find_if(camera_last_.begin(), camera_last_.end(),
                        [&](const CameraClock& c) { return c.camera_id == camera_id; });
  camera->last_s = t;
  camera->last_frame_number = frame_number;
  last_frame_number_ = frame_number;
  newest_s_ = std::max(newest_s_, t);
  if (open_k_ && instant_complete(*open_k_)) emit(*open_k_, false);
}

void FormationSampler::set_aside(std::uint32_t camera_id, std::uint32_t frame_number, double t) {
  ++counters_.frames_other_clock;
  const double clock_reset_s =
      config_.clock_reset_s > 0.0 ? config_.clock_reset_s : 2.0 * config_.step_s;
  if (!other_.active || std::abs(t - other_.newest_s) > clock_reset_s) {
    // Not the other clock seen before: a new one, and what was set aside is not its.
    other_ = OtherClock{true, false, t, newest_s_};
    pending_.clear();
  } else {
    if (t > other_.newest_s + time_epsilon_s) other_.advancing = true;
    other_.newest_s = std::max(other_.newest_s, t);
    other_.seen_at_s = newest_s_;
  }
  if (!pending_.empty() && std::abs(t - pending_.back().time_s) > clock_reset_s) pending_.clear();
  pending_.push_back(PendingFrame{camera_id, frame_number, t, frame_scratch_});

  int distinct_times = 0;
  double last_s = std::nan("");
  std::vector<double> times;
  times.reserve(pending_.size());
  for (const PendingFrame& f : pending_) times.push_back(f.time_s);
  std::sort(times.begin(), times.end());
  for (const double time_s : times) {
    if (!(std::abs(time_s - last_s) <= time_epsilon_s)) ++distinct_times;
    last_s = time_s;
  }
  if (distinct_times >= config_.clock_confirm_times ||
      pending_.size() >= config_.max_pending_frames) {
    switch_clock();
  }
}

// The set-aside frames' clock takes over: a new stream, then those frames in their order.
void FormationSampler::switch_clock() {
  ++counters_.clock_resets;
  std::vector<PendingFrame> frames = std::move(pending_);
  // The clock left behind becomes the other clock: if it comes back, that is a conflict.
  const OtherClock left{true, next_k_ > 1, newest_s_, frames.back().time_s};
  const bool conflict = conflict_;
  restart();
  other_ = left;
  conflict_ = conflict;
  for (PendingFrame& f : frames) {
    frame_scratch_ = std::move(f.detections);
    place_frame(f.camera_id, f.frame_number, f.time_s);
  }
}

void FormationSampler::apply_detections(std::uint32_t camera_id, double time_s) {
  auto camera = std::find_if(camera_last_.begin(), camera_last_.end(),
                             [&](const CameraClock& c) { return c.camera_id == camera_id; });
  if (camera == camera_last_.end()) {
    camera_last_.push_back(CameraClock{camera_id, time_s, time_s, 0});
  } else {
    camera->newest_s = std::max(camera->newest_s, time_s);
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
  for (const CameraClock& camera : camera_last_) {
    if (camera.newest_s >= newest_s_ - live_window && camera.newest_s < sample_s - time_epsilon_s) {
      return false;
    }
  }
  return true;
}

Formation FormationSampler::build_formation(const StateCodec& codec, const FieldSize& field,
                                            std::vector<FormationRobot> robots,
                                            const Formation* previous) {
  Formation formation;
  build_formation(codec, field, robots, previous, formation);
  return formation;
}

Formation FormationSampler::formation_at(const StateCodec& codec, const FieldSize& field,
                                         const std::vector<Point>& positions,
                                         const Formation* previous) {
  std::vector<FormationRobot> robots(positions.size());
  for (std::size_t id = 0; id < positions.size(); ++id) {
    robots[id].robot_id = static_cast<std::uint32_t>(id);
    robots[id].position = positions[id];
  }
  return build_formation(codec, field, std::move(robots), previous);
}

void FormationSampler::build_formation(const StateCodec& codec, const FieldSize& field,
                                       std::vector<FormationRobot>& robots,
                                       const Formation* previous, Formation& formation) {
  formation.time_s = 0.0;
  formation.frame_number = 0;
  formation.centroid = Point{};
  const auto by_id = [](const FormationRobot& a, const FormationRobot& b) {
    return a.robot_id < b.robot_id;
  };
  // The sampler hands its robots over in id order already: no sort code to run (cold) then.
  if (!std::is_sorted(robots.begin(), robots.end(), by_id)) {
    std::sort(robots.begin(), robots.end(), by_id);
  }
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
    robot.state =
        codec.encode(RobotState{formation.centroid_cell, robot.cell, robot.previous_cell});
  }
  formation.robots.swap(robots);
}

void FormationSampler::emit(std::int64_t k, bool forced) {
  const double sample_s = instant(k);
  next_k_ = k + 1;
  open_k_.reset();

  const double fresh_s = std::min(config_.robot_timeout_s, config_.step_s);
  std::vector<FormationRobot>& robots = robots_scratch_;
  robots.clear();
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

  const bool continues = previous_ && k - previous_k_ == 1 && !conflict_;
  if (previous_ && !continues) ++counters_.chain_breaks;
  if (conflict_) ++counters_.samples_in_conflict;
  FormationSample& sample = sample_scratch_;
  build_formation(codec_, field_, robots, continues ? &*previous_ : nullptr, sample.formation);
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
  previous_k_ = k;
  // This sample becomes the previous one after the handler has run (the predictor sends its
  // prediction from there, so nothing else should come first), by swapping buffers rather than
  // copying; also if the handler throws, or the next sample would follow a stale formation.
  // A handler that starts a new stream (restart()) forgets this sample too.
  struct BecomesPrevious {
    FormationSampler& sampler;
    std::uint64_t restarts;
    ~BecomesPrevious() {
      if (sampler.restarts_ != restarts) return;
      if (!sampler.previous_) sampler.previous_.emplace();
      std::swap(*sampler.previous_, sampler.sample_scratch_.formation);
    }
  } becomes_previous{*this, restarts_};
  if (on_sample_) on_sample_(sample);
}

void FormationSampler::restart() {
  ++restarts_;
  if (previous_) ++counters_.chain_breaks;
  previous_.reset();
  anchored_ = false;
  open_k_.reset();
  next_k_ = 0;
  camera_last_.clear();
  pending_.clear();
  other_ = OtherClock{};
  conflict_ = false;
  for (const std::uint32_t id : observed_ids_) observations_[id].seen = false;
  observed_ids_.clear();
}

namespace {
struct RejectionKind {
  const char* key;
  std::uint64_t SamplerCounters::*counter;
  const char* what;
};
// Every way the sampler refuses or sets aside input, in the order status lines print them.
constexpr RejectionKind rejection_kinds[] = {
    {"non_finite", &SamplerCounters::robots_non_finite, "robots with NaN or infinite coordinates"},
    {"out_of_range", &SamplerCounters::robots_out_of_range, "robots with coordinates beyond 100 m"},
    {"bad_id", &SamplerCounters::robots_bad_id,
     "robots without an id or with an id over the limit"},
    {"duplicate_ids", &SamplerCounters::robots_duplicate_in_frame,
     "robots reported twice in one frame (the more confident kept)"},
    {"bad_time", &SamplerCounters::frames_bad_time, "frames with a NaN or infinite t_capture"},
    {"bad_camera", &SamplerCounters::frames_bad_camera, "frames with a camera id over the limit"},
    {"too_many_robots", &SamplerCounters::frames_too_many_robots,
     "frames with more robots than a team can have"},
    {"late", &SamplerCounters::frames_late, "frames older than the last sample (out of order)"},
    {"duplicate_frames", &SamplerCounters::frames_duplicate, "frames received twice"},
    {"other_clock", &SamplerCounters::frames_other_clock,
     "frames set aside as another data clock's (restart, gap or second sender)"},
    {"bad_geometry", &SamplerCounters::geometry_invalid,
     "geometry packets with a zero, negative or non-finite field size"},
    {"empty_packets", &SamplerCounters::packets_empty,
     "packets with neither detection nor geometry (another message type?)"},
    {"clock_conflicts", &SamplerCounters::clock_conflicts,
     "clock conflicts (two senders interleaving): no transition counted meanwhile"},
};
}  // namespace

std::string describe_rejections(const SamplerCounters& counters) {
  std::string out;
  for (const RejectionKind& kind : rejection_kinds) {
    if (!out.empty()) out += ' ';
    out += kind.key;
    out += '=';
    out += std::to_string(counters.*kind.counter);
  }
  out += " clock_resets=" + std::to_string(counters.clock_resets);
  out += " field_changes=" + std::to_string(counters.field_changes);
  return out;
}

std::vector<std::string> new_rejections(const SamplerCounters& before,
                                        const SamplerCounters& after) {
  std::vector<std::string> out;
  for (const RejectionKind& kind : rejection_kinds) {
    const std::uint64_t now = after.*kind.counter;
    const std::uint64_t then = before.*kind.counter;
    if (now <= then) continue;
    out.push_back(std::to_string(now - then) + " " + kind.what + " [" + kind.key + "] (" +
                  std::to_string(now) + " in all)");
  }
  return out;
}

}  // namespace ssl_formation
