#pragma once
// Turns a stream of SSL-Vision packets into formations on the data's own clock (DESIGN.md §3):
// one sample every `step` seconds of t_capture, robots merged across cameras, geometry packets
// updating the field size, and the velocity-reset rules for new robots and gaps.
//
// Pure: no sockets, clocks or threads. The daemons, log replay and tests all drive this class.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ssl_formation/formation.hpp"
#include "ssl_formation/grid.hpp"
#include "ssl_formation/state.hpp"
#include "ssl_formation/vision_frame.hpp"

class SSL_WrapperPacket;

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
  // A frame more than this far from the clock (behind or ahead) belongs to another clock: a
  // restarted sender, a feed resuming after a gap, or a second sender on the same group. 0 means
  // two steps; network reordering is milliseconds, never that much.
  double clock_reset_s = 0.0;
  // Frames of another clock are set aside. When they show this many distinct t_capture values
  // with no frame of the current clock between them, the sampler takes that clock over (a
  // restart or a resumed feed): it starts over, then uses the set-aside frames, so nothing is
  // lost but the transition across. One stray old or future frame never moves the clock.
  int clock_confirm_times = 3;
  std::size_t max_pending_frames = 256;  // the set-aside frames also take over at this many
  // Frames of two advancing clocks interleaving (a second sender, e.g. a replay beside a live
  // feed) are a clock conflict: samples are still handed on (from the current clock only) but
  // count no transition until the other clock has been silent this long on the current clock.
  // 0 means four steps.
  double clock_conflict_hold_s = 0.0;
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
  std::uint64_t robots_non_finite = 0;          // NaN or inf coordinates
  std::uint64_t robots_out_of_range = 0;        // |x| or |y| beyond max_abs_coordinate_mm
  std::uint64_t robots_bad_id = 0;              // missing id or id over max_robot_id
  std::uint64_t robots_duplicate_in_frame = 0;  // same id twice in one frame: best kept
  std::uint64_t frames_bad_time = 0;            // NaN/inf t_capture
  std::uint64_t frames_bad_camera = 0;          // camera id over max_camera_id
  std::uint64_t frames_too_many_robots = 0;
  std::uint64_t frames_without_opponent = 0;  // empty frames (still count for completion)
  std::uint64_t frames_late = 0;              // older than the last sample: out of order
  std::uint64_t geometry_invalid = 0;         // zero, negative or non-finite field size
  std::uint64_t field_changes = 0;
  std::uint64_t clock_resets = 0;         // switches to another clock (restart, resumed feed)
  std::uint64_t frames_other_clock = 0;   // frames set aside as another clock's
  std::uint64_t frames_duplicate = 0;     // same camera, frame number and t_capture again
  std::uint64_t packets_empty = 0;        // neither detection nor geometry (another message?)
  std::uint64_t clock_conflicts = 0;      // episodes of two clocks interleaving
  std::uint64_t samples_in_conflict = 0;  // samples that counted no transition because of one
  std::uint64_t samples = 0;
  std::uint64_t samples_empty = 0;   // no opponent robot in the sample: not handed on
  std::uint64_t samples_forced = 0;  // handed on without every live camera (a dropped frame)
  std::uint64_t chain_breaks = 0;    // gaps, field changes and clock resets
  std::uint64_t transitions = 0;
};

// "non_finite=0 out_of_range=0 ..." : every refusal counter, for status lines.
std::string describe_rejections(const SamplerCounters& counters);
// One sentence per kind of refusal that grew from `before` to `after` ("2 frames with a camera id
// over the limit (5 in all)"), for a daemon to log as warnings when new kinds of bad input arrive.
std::vector<std::string> new_rejections(const SamplerCounters& before,
                                        const SamplerCounters& after);

class FormationSampler {
 public:
  using SampleHandler = std::function<void(const FormationSample&)>;

  // Throws std::invalid_argument for a step that is not positive and finite.
  FormationSampler(SamplerConfig config, SampleHandler on_sample);

  // Feeds one packet; calls the handler for every sample it completes (zero, one or two).
  void add(const VisionFrame& frame);
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
                                   std::vector<FormationRobot> robots, const Formation* previous);
  // Robots 0, 1, 2, ... at these normalised positions, for callers that place robots by hand
  // (evaluation of the paper's plays, benchmarks, tests).
  static Formation formation_at(const StateCodec& codec, const FieldSize& field,
                                const std::vector<Point>& positions, const Formation* previous);
  // The same into `out`, whose robots vector is swapped with `robots` (both keep their memory).
  static void build_formation(const StateCodec& codec, const FieldSize& field,
                              std::vector<FormationRobot>& robots, const Formation* previous,
                              Formation& out);

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
  struct CameraClock {
    std::uint32_t camera_id = 0;
    double newest_s = 0.0;
    double last_s = 0.0;  // of its last frame, with:
    std::uint32_t last_frame_number = 0;
  };
  // A frame of another clock, set aside until that clock takes over or the current one goes on.
  struct PendingFrame {
    std::uint32_t camera_id = 0;
    std::uint32_t frame_number = 0;
    double time_s = 0.0;
    std::vector<Detection> detections;
  };
  // The most recent other clock seen: lets a second interleaving sender be told from a stray frame.
  struct OtherClock {
    bool active = false;
    bool advancing = false;  // seen at two or more distinct times
    double newest_s = 0.0;
    double seen_at_s = 0.0;  // the current clock's newest time when last seen
  };

  void add_geometry(std::int32_t field_length, std::int32_t field_width);
  void add_detection(const VisionDetection& frame);
  void place_frame(std::uint32_t camera_id, std::uint32_t frame_number, double time_s);
  void set_aside(std::uint32_t camera_id, std::uint32_t frame_number, double time_s);
  void switch_clock();
  void apply_detections(std::uint32_t camera_id, double time_s);
  bool instant_complete(std::int64_t k) const;
  void emit(std::int64_t k, bool forced);
  double instant(std::int64_t k) const {
    return anchor_s_ + static_cast<double>(k) * config_.step_s;
  }
  void restart();

  SamplerConfig config_;
  StateCodec codec_;
  SampleHandler on_sample_;
  FieldSize field_;
  SamplerCounters counters_;

  VisionFrame packet_scratch_;  // add(SSL_WrapperPacket) converts into this
  std::vector<Detection> frame_scratch_;
  std::vector<Observation> observations_;    // indexed by robot id
  std::vector<std::uint32_t> observed_ids_;  // ids with an observation, sorted
  std::vector<CameraClock> camera_last_;
  std::vector<PendingFrame> pending_;
  OtherClock other_;
  bool conflict_ = false;

  bool anchored_ = false;
  double anchor_s_ = 0.0;
  double newest_s_ = 0.0;
  std::int64_t next_k_ = 0;
  std::optional<std::int64_t> open_k_;
  std::uint32_t last_frame_number_ = 0;

  std::optional<Formation> previous_;
  std::int64_t previous_k_ = 0;
  std::uint64_t restarts_ = 0;  // calls of restart(), so emit() sees one made by its handler
  // Reused from sample to sample, so that a steady stream allocates nothing.
  std::vector<FormationRobot> robots_scratch_;
  FormationSample sample_scratch_;
};

}  // namespace ssl_formation
