#include "ssl_formation/vision/sampler.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation {
inline namespace vision {

namespace {
constexpr double time_epsilon_s = 1e-9;
}  // namespace

std::optional<Sampling> parse_sampling(std::string_view text) {
  if (text == "step") return Sampling::step;
  if (text == "frame") return Sampling::frame;
  return std::nullopt;
}

std::string_view to_string(Sampling sampling) {
  return sampling == Sampling::frame ? "frame" : "step";
}

FormationSampler::FormationSampler(SamplerConfig config, SampleHandler on_sample)
    : config_(config),
      codec_(config.grid),
      clock_(config.clock_config()),  // checks the step and the interval
      on_sample_(std::move(on_sample)),
      field_(config.field),
      attack_inference_(config.attack_window_s) {
  if (!config_.infer_attacks) attacks_ = config_.opponent_attacks;
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
  break_chain();
}

void FormationSampler::break_chain() {
  if (previous_ || !history_.empty()) ++counters_.chain_breaks;
  previous_.reset();
  history_.clear();
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
                     [&](const FrameDetection& d) { return d.robot_id == robot.robot_id; });
    if (same != frame_scratch_.end()) {
      ++counters_.robots_duplicate_in_frame;
      if (robot.confidence > same->confidence) *same = {robot.robot_id, x, y, robot.confidence};
      continue;
    }
    frame_scratch_.push_back({robot.robot_id, x, y, robot.confidence});
  }
  counters_.robots_accepted += frame_scratch_.size();
  if (frame_scratch_.empty()) ++counters_.frames_without_opponent;
  clock_.place(*this, ClockFrame{frame.camera_id, frame.frame_number, t}, frame_scratch_);
}

void FormationSampler::on_event(ClockEvent event) {
  switch (event) {
    case ClockEvent::frame_late:
      ++counters_.frames_late;
      break;
    case ClockEvent::frame_duplicate:
      ++counters_.frames_duplicate;
      break;
    case ClockEvent::frame_set_aside:
      ++counters_.frames_other_clock;
      break;
    case ClockEvent::conflict:
      ++counters_.clock_conflicts;
      break;
  }
}

void FormationSampler::on_restart(ClockRestart /*why*/) {
  ++counters_.clock_resets;
  forget_stream();
}

// The frame is used: its robots become the newest observations.
void FormationSampler::on_frame(const ClockFrame& frame,
                                const std::vector<FrameDetection>& detections) {
  const double time_s = frame.time_s;
  const std::uint32_t camera_id = frame.camera_id;
  for (const FrameDetection& d : detections) {
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
  last_frame_number_ = frame.frame_number;
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

namespace {

// build_formation(), calling continued(robot, then) for every robot also in `previous` (`then`
// its entry there) once its state is known. `find_in_previous(id)` is that robot's entry in
// `previous`, or none; it is asked for ids in increasing order. `known_cell(robot)` is the
// robot's cell if the caller knows it already (else null), asked in the same order.
template <class FindInPrevious, class Continued, class KnownCell>
void encode_formation(const StateCodec& codec, const FieldSize& field,
                      std::vector<FormationRobot>& robots, const Formation* previous,
                      Formation& formation, FindInPrevious find_in_previous, Continued continued,
                      KnownCell known_cell) {
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
    const Cell* known = known_cell(robot);
    robot.cell = known ? *known : grid.cell_of(robot.position, field);
    const FormationRobot* before = previous ? find_in_previous(robot.robot_id) : nullptr;
    robot.previous_cell = before ? before->cell : robot.cell;
    robot.state =
        codec.encode(RobotState{formation.centroid_cell, robot.cell, robot.previous_cell});
    if (before) continued(robot, *before);
  }
  formation.robots.swap(robots);
}

}  // namespace

void FormationSampler::build_formation(const StateCodec& codec, const FieldSize& field,
                                       std::vector<FormationRobot>& robots,
                                       const Formation* previous, Formation& formation) {
  encode_formation(
      codec, field, robots, previous, formation,
      [previous](std::uint32_t id) { return previous->find(id); },
      [](const FormationRobot&, const FormationRobot&) {},
      [](const FormationRobot&) -> const Cell* { return nullptr; });
}

// The clock hands an instant on: its sample is built from the freshest observations.
void FormationSampler::on_instant(const ClockInstant& instant) {
  const std::int64_t k = instant.k;
  const double sample_s = instant.time_s;
  const double fresh_s = config_.robot_fresh_window_s();
  std::vector<FormationRobot>& robots = robots_scratch_;
  robots.clear();
  for (const std::uint32_t id : observed_ids_) {
    Observation& obs = observations_[id];
    if (obs.time_s <= sample_s - fresh_s + time_epsilon_s) continue;
    FormationRobot& robot = robots.emplace_back();  // built in place, not copied in
    robot.robot_id = id;
    robot.observed = !obs.in_instant;
    obs.in_instant = true;
    robot.feed_position = Point{obs.sum_x / obs.weight, obs.sum_y / obs.weight};
    robot.position = normalise(robot.feed_position, config_.opponent_attacks);
  }
  if (robots.empty()) {
    ++counters_.samples_empty;
    break_chain();
    return;
  }
  if (config_.infer_attacks) {
    inference_scratch_.clear();
    for (const FormationRobot& robot : robots) {
      inference_scratch_.push_back({robot.robot_id, robot.feed_position});
    }
    if (attack_inference_.add(sample_s, inference_scratch_, field_)) {
      // Cells on either side of a change of ends do not compare: no transition spans it.
      if (attacks_) {
        ++counters_.attack_switches;
        break_chain();
      }
      attacks_ = attack_inference_.direction();
    }
    if (!attacks_) {
      ++counters_.samples_undirected;
      return;
    }
    for (FormationRobot& robot : robots) robot.position = normalise(robot.feed_position, *attacks_);
  }
  if (config_.sampling == Sampling::frame) {
    on_frame_instant(instant, robots);
    return;
  }

  const bool continues = previous_ && k - previous_k_ == 1 && !instant.in_conflict;
  if (previous_ && !continues) ++counters_.chain_breaks;
  if (instant.in_conflict) ++counters_.samples_in_conflict;
  const Formation* previous = continues ? &*previous_ : nullptr;
  FormationSample& sample = build_sample(instant, robots, previous, previous);
  previous_k_ = k;
  // This sample becomes the previous one after the handler has run (the predictor sends its
  // prediction from there, so nothing else should come first), by swapping buffers rather than
  // copying; also if the handler throws, or the next sample would follow a stale formation.
  // A handler that starts a new stream (forget_stream()) forgets this sample too.
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

// The sample of an instant, into sample_scratch_: its formation from `robots` (whose storage it
// takes) with the previous cells from `before` (none: velocity 0), and a transition from
// `before` for every robot in both. `latest` is the sample before this one in the same chain, if
// any: a robot carried over from it keeps its cell there (a real log's packets each see half the
// field, so half of every instant's robots are the last one's again).
FormationSample& FormationSampler::build_sample(const ClockInstant& instant,
                                                std::vector<FormationRobot>& robots,
                                                const Formation* before, const Formation* latest) {
  FormationSample& sample = sample_scratch_;
  sample.transitions.clear();
  // `before` is a formation of this sampler's, sorted by id with each id once, and the robots
  // are asked for in id order: one walk through it finds each, as Formation::find would, and
  // the transitions are counted in the same pass.
  const FormationRobot* next_before = before ? before->robots.data() : nullptr;
  const FormationRobot* const before_end =
      before ? before->robots.data() + before->robots.size() : nullptr;
  // The same walk through `latest`. Its cells were computed on the same field (a new field
  // breaks the chain) from positions normalised the same way (so does a change of ends): an
  // equal position is an equal cell.
  const FormationRobot* next_latest = latest ? latest->robots.data() : nullptr;
  const FormationRobot* const latest_end =
      latest ? latest->robots.data() + latest->robots.size() : nullptr;
  encode_formation(
      codec_, field_, robots, before, sample.formation,
      [&](std::uint32_t id) -> const FormationRobot* {
        while (next_before != before_end && next_before->robot_id < id) ++next_before;
        return next_before != before_end && next_before->robot_id == id ? next_before : nullptr;
      },
      [&](const FormationRobot& robot, const FormationRobot& then) {
        // Frame sampling counts a robot at the instants a frame saw it: one carried over from
        // an earlier frame would count that frame's transition again, and robots would weigh
        // by how the cameras split the field. (A step sample's robots are all counted, as the
        // paper does.)
        if (robot.observed || config_.sampling == Sampling::step) {
          sample.transitions.push_back({robot.robot_id, then.state, robot.state});
        }
      },
      [&](const FormationRobot& robot) -> const Cell* {
        if (robot.observed) return nullptr;
        while (next_latest != latest_end && next_latest->robot_id < robot.robot_id) ++next_latest;
        return next_latest != latest_end && next_latest->robot_id == robot.robot_id &&
                       next_latest->position == robot.position
                   ? &next_latest->cell
                   : nullptr;
      });
  sample.formation.time_s = instant.time_s;
  sample.formation.frame_number = last_frame_number_;
  sample.formation.opponent_attacks = attacks_.value_or(config_.opponent_attacks);
  ++counters_.samples;
  if (instant.forced) ++counters_.samples_forced;
  counters_.transitions += sample.transitions.size();
  return sample;
}

// Frame sampling: the sample's previous formation is the one sampled step_s before it.
void FormationSampler::on_frame_instant(const ClockInstant& instant,
                                        std::vector<FormationRobot>& robots) {
  const double sample_s = instant.time_s;
  // A gap longer than a step: nothing before it can be anyone's previous.
  if (!history_.empty() &&
      sample_s - history_.back().time_s > config_.step_s + config_.history_tolerance_s) {
    break_chain();
  }
  // Samples older than step_s (and the tolerance) can no longer be anyone's previous.
  const double oldest_s = sample_s - config_.step_s - config_.history_tolerance_s;
  while (!history_.empty() && history_.front().time_s < oldest_s - time_epsilon_s) {
    history_.pop_front();
  }
  // The sample nearest step_s earlier, within the tolerance; the earlier of two equally near.
  const double wanted_s = sample_s - config_.step_s;
  const Formation* before = nullptr;
  double best_gap = config_.history_tolerance_s + time_epsilon_s;
  for (std::size_t i = 0; i < history_.size(); ++i) {
    const Formation& f = history_[i];
    const double gap = std::abs(f.time_s - wanted_s);
    if (gap < best_gap) {
      best_gap = gap;
      before = &f;
    }
    if (f.time_s > wanted_s) break;
  }
  if (instant.in_conflict) {
    ++counters_.samples_in_conflict;
    before = nullptr;
  }
  FormationSample& sample =
      build_sample(instant, robots, before, history_.empty() ? nullptr : &history_.back());
  // The sample joins the history after the handler has run (the predictor sends its prediction
  // from there), by swapping buffers rather than copying (build_sample() overwrites all of
  // sample_scratch_ next time); a handler that starts a new stream forgets it too.
  struct JoinsHistory {
    FormationSampler& sampler;
    std::uint64_t restarts;
    ~JoinsHistory() {
      if (sampler.restarts_ != restarts) return;
      sampler.history_.push_back_swap(sampler.sample_scratch_.formation);
    }
  } joins_history{*this, restarts_};
  if (on_sample_) on_sample_(sample);
}

void FormationHistory::push_back_swap(Formation& formation) {
  if (size_ == slots_.size()) {
    // Full: the slots in order from the oldest, then new ones after them.
    std::rotate(slots_.begin(), slots_.begin() + static_cast<std::ptrdiff_t>(head_), slots_.end());
    head_ = 0;
    slots_.resize(std::max<std::size_t>(16, 2 * slots_.size()));
  }
  std::swap(slots_[slot(size_)], formation);
  ++size_;
}

void FormationSampler::start_new_stream() {
  forget_stream();
  clock_.reset();
  // Another file may be another match: the attack direction is inferred anew.
  if (config_.infer_attacks) {
    attack_inference_.reset();
    attacks_.reset();
  }
}

void FormationSampler::set_opponent(TeamColor color, std::optional<AttackDirection> attacks) {
  // Switches before the first sample change nothing sampled (the referee's first message
  // replacing the defaults): they are not counted as changes.
  const bool sampled = counters_.samples > 0;
  if (color != config_.opponent_color) {
    config_.opponent_color = color;
    if (sampled) ++counters_.opponent_switches;
    // The other team's robots share the ids: nothing seen of the old opponent may stay, nor
    // the side inferred from where its goalkeeper stood.
    break_chain();
    for (const std::uint32_t id : observed_ids_) observations_[id].seen = false;
    observed_ids_.clear();
    if (config_.infer_attacks) {
      attack_inference_.reset();
      attacks_.reset();
    }
  }
  if (attacks) {
    if (!config_.infer_attacks && attacks_ == attacks) return;
    if (attacks_ && *attacks_ != *attacks) {
      if (sampled) ++counters_.attack_switches;
      break_chain();
    }
    config_.infer_attacks = false;
    config_.opponent_attacks = *attacks;
    attacks_ = attacks;
  } else if (!config_.infer_attacks) {
    // From a side that was known to one inferred: no sample until the inference decides.
    config_.infer_attacks = true;
    attack_inference_.reset();
    attacks_.reset();
    break_chain();
  }
}

void FormationSampler::forget_stream() {
  ++restarts_;
  break_chain();
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

std::vector<std::pair<std::string_view, std::uint64_t>> rejection_counts(
    const SamplerCounters& counters) {
  std::vector<std::pair<std::string_view, std::uint64_t>> out;
  out.reserve(std::size(rejection_kinds));
  for (const RejectionKind& kind : rejection_kinds) {
    out.emplace_back(kind.key, counters.*kind.counter);
  }
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

}  // namespace vision
}  // namespace ssl_formation
