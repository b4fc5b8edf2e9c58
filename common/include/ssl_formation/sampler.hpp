#pragma once
// Turns a stream of SSL-Vision packets into formations on the data's own clock (DESIGN.md §3):
// one sample every `step` seconds of t_capture, robots merged across cameras, geometry packets
// updating the field size, and the velocity-reset rules for new robots and gaps.
//
// Pure: no sockets, clocks or threads. The daemons, log replay and tests all drive this class.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ssl_formation/formation.hpp"
#include "ssl_formation/grid.hpp"
#include "ssl_formation/state.hpp"

class SSL_WrapperPacket;
class SSL_DetectionFrame;
class SSL_GeometryData;

namespace ssl_formation {

struct SamplerConfig {
  Grid grid{3, 2};
  double step_s = 2.0;
  TeamColor opponent_color = TeamColor::yellow;
  AttackDirection opponent_attacks = AttackDirection::positive_x;
  FieldSize field;  // used until a valid geometry packet arrives
  bool use_geometry = true;
  // A robot is in a sample only if seen within min(robot_timeout_s, step_s) before it.
  double robot_timeout_s = 0.5;
  // A camera counts as live (a sample waits for it) if it sent a frame within
  // max(camera_timeout_s, 1.5 * step_s): a camera of a 2 s simulated feed is live, a dead one
  // stops holding samples back after that.
  double camera_timeout_s = 1.0;
  // Frames more than this far behind the newest frame mean the data clock restarted (a new log,
  // a restarted simulator or producer): the sampler starts over instead of dropping everything
  // as late. 0 means two steps; network reordering is milliseconds, never that much.
  double clock_reset_s = 0.0;
  std::uint32_t max_robot_id = 1000;
  std::uint32_t max_camera_id = 63;
  std::uint32_t max_robots_per_frame = 32;  // per team; more than this is not a real frame
  double max_abs_coordinate_mm = 100000.0;  // 100 m: anything beyond is nonsense
  // Detections of one robot by overlapping cameras this close in time are averaged.
  double same_instant_s = 0.001;
};

// Every packet, frame or robot the sampler refused, by reason, and what it produced.
struct SamplerCounters {
  std::uint64_t packets = 0;
  std::uint64_t detection_frames = 0;
  std::uint64_t geometry_packets = 0;
  std::uint64_t robots_accepted = 0;
  std::uint64_t robots_non_finite = 0;        // NaN or inf coordinates
  std::uint64_t robots_out_of_range = 0;      // |x| or |y| beyond max_abs_coordinate_mm
  std::uint64_t robots_bad_id = 0;            // missing id or id over max_robot_id
  std::uint64_t robots_duplicate_in_frame = 0;  // same id twice in one frame: best kept
  std::uint64_t frames_bad_time = 0;          // NaN/inf t_capture
  std::uint64_t frames_bad_camera = 0;        // camera id over max_camera_id
  std::uint64_t frames_too_many_robots = 0;
  std::uint64_t frames_without_opponent = 0;  // empty frames (still count for completion)
  std::uint64_t frames_late = 0;              // older than the last sample: out of order
  std::uint64_t geometry_invalid = 0;         // zero, negative or non-finite field size
  std::uint64_t field_changes = 0;
  std::uint64_t clock_resets = 0;
  std::uint64_t samples = 0;
  std::uint64_t samples_empty = 0;  // no opponent robot in the sample: not handed on
  std::uint64_t samples_forced = 0;  // handed on without every live camera (a dropped frame)
  std::uint64_t chain_breaks = 0;   // gaps, field changes and clock resets
  std::uint64_t transitions = 0;
};

class FormationSampler {
 public:
  using SampleHandler = std::function<void(const FormationSample&)>;

  // Throws std::invalid_argument for a step that is not positive and finite.
  FormationSampler(SamplerConfig config, SampleHandler on_sample);

  // Feeds one packet; calls the handler for every sample it completes (zero, one or two).
  void add(const SSL_WrapperPacket& packet);

  // Forgets the stream so far (cameras, clock, previous formation) but keeps the field size and
  // the counters: the next packet starts a new stream, and no transition spans the two.
  void start_new_stream() { restart(); }

  const SamplerConfig& config() const { return config_; }
  const StateCodec& codec() const { return codec_; }
  const FieldSize& field() const { return field_; }
  const SamplerCounters& counters() const { return counters_; }

  // Encodes a formation's robots as states from their positions, for callers that build
  // formations themselves (the simulated producer, evaluation).
  static Formation build_formation(const StateCodec& codec, const FieldSize& field,
                                   std::vector<FormationRobot> robots,
                                   const Formation* previous);

 private:
  struct Observation {
    double time_s = 0.0;
    double sum_x = 0.0;
    double sum_y = 0.0;
    double weight = 0.0;
    std::uint32_t camera_id = 0;
    bool seen = false;
  };
  struct Detection {
    std::uint32_t robot_id;
    double x;
    double y;
    float confidence;
  };

  void add_geometry(const SSL_GeometryData& geometry);
  void add_detection(const SSL_DetectionFrame& frame);
  void apply_detections(std::uint32_t camera_id, double time_s);
  bool instant_complete(std::int64_t k) const;
  void emit(std::int64_t k, bool forced);
  double instant(std::int64_t k) const { return anchor_s_ + static_cast<double>(k) * config_.step_s; }
  void restart();

  SamplerConfig config_;
  StateCodec codec_;
  SampleHandler on_sample_;
  FieldSize field_;
  SamplerCounters counters_;

  std::vector<Detection> frame_scratch_;
  std::vector<Observation> observations_;  // indexed by robot id
  std::vector<std::uint32_t> observed_ids_;  // ids with an observation, sorted
  std::vector<std::pair<std::uint32_t, double>> camera_last_;  // camera id, newest t_capture

  bool anchored_ = false;
  double anchor_s_ = 0.0;
  double newest_s_ = 0.0;
  std::int64_t next_k_ = 0;
  std::optional<std::int64_t> open_k_;
  std::uint32_t last_frame_number_ = 0;

  std::optional<Formation> previous_;
  std::int64_t previous_k_ = 0;
  FormationSample sample_scratch_;
};

}  // namespace ssl_formation
