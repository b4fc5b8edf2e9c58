#pragma once
// Turns a stream of SSL-Vision packets into formations on the data's own clock (docs/models.md):
// one sample every `step` seconds of t_capture (the paper's sampling), or one at every frame
// instant with each robot's previous cell taken from `step` seconds earlier (rolling sampling);
// robots merged across cameras, geometry packets updating the field size, and the
// velocity-reset rules for new robots and gaps. Which frames count and when a sample is complete
// is DataClock's to decide.
//
// Pure: no sockets, clocks or threads. The daemons, log replay and tests all drive this class.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/state.hpp"
#include "ssl_formation/vision/attack_inference.hpp"
#include "ssl_formation/vision/data_clock.hpp"
#include "ssl_formation/vision/vision_frame.hpp"

class SSL_WrapperPacket;

namespace ssl_formation {
inline namespace vision {

// How often formations are sampled.
//   step   one every step_s of the data clock; a transition joins two consecutive samples. The
//          paper's protocol: a prediction every step, and few samples to learn from.
//   frame  one at every frame instant; a robot's previous cell is its cell step_s earlier, from
//          the sample nearest that time, and a transition joins each sample to the one step_s
//          before it. Sixty times the samples at 60 Hz, and a prediction at every frame.
enum class Sampling { step, frame };
std::optional<Sampling> parse_sampling(std::string_view text);  // "step" or "frame"
std::string_view to_string(Sampling sampling);

// The sampler's settings. The data clock's (step_s, camera_timeout_s, clock_reset_s,
// clock_confirm_times, max_pending_frames, clock_conflict_hold_s) and their rules are
// DataClockConfig's.
struct SamplerConfig : DataClockConfig {
  Grid grid{3, 2};
  TeamColor opponent_color = TeamColor::yellow;
  AttackDirection opponent_attacks = AttackDirection::positive_x;
  FieldSize field;  // used until a valid geometry packet arrives
  bool use_geometry = true;
  // A robot is in a sample only if seen within robot_fresh_window_s() = min(robot_timeout_s,
  // step_s) before it.
  double robot_timeout_s = 0.5;
  std::uint32_t max_robot_id = 1000;
  std::uint32_t max_camera_id = 63;
  std::uint32_t max_robots_per_frame = 32;  // per team; more than this is not a real frame
  double max_abs_coordinate_mm = 100000.0;  // 100 m: anything beyond is nonsense
  // Detections of one robot by overlapping cameras this close in time are averaged.
  double same_instant_s = 0.001;

  Sampling sampling = Sampling::step;
  // --opponent-attacks auto: the direction is inferred from where the opponent's goalkeeper
  // stands (AttackInference, over attack_window_s), opponent_attacks is only its first guess
  // never used, and no sample is handed on until the direction is known. A switch (the teams
  // changed ends) breaks the chain: cells before and after do not compare.
  bool infer_attacks = false;
  double attack_window_s = 10.0;
  // Frame sampling: instants are frame_resolution_s apart (so every frame time is one); the
  // sample standing for "step_s earlier" is the one nearest that time within
  // history_tolerance_s (none there: no previous cell, no transition); a robot is in a sample if
  // seen within frame_robot_timeout_s. Samples more than step_s + history_tolerance_s apart are a
  // gap: nothing before it can be anyone's previous, and it counts as a chain break.
  double frame_resolution_s = 0.001;
  double history_tolerance_s = 0.05;
  double frame_robot_timeout_s = 0.1;

  double robot_fresh_window_s() const {
    return std::min(robot_timeout_s, sampling == Sampling::frame ? frame_robot_timeout_s : step_s);
  }
  // The clock's settings, with the instant interval the sampling implies.
  DataClockConfig clock_config() const {
    DataClockConfig clock = *this;
    clock.instant_interval_s = sampling == Sampling::frame ? frame_resolution_s : 0.0;
    return clock;
  }
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
  std::uint64_t samples_empty = 0;       // no opponent robot in the sample: not handed on
  std::uint64_t samples_forced = 0;      // handed on without every live camera (a dropped frame)
  std::uint64_t chain_breaks = 0;        // gaps, field changes and clock resets
  std::uint64_t samples_undirected = 0;  // not handed on: the attack direction is not known yet
  // After the first sample (a setting replaced before it changes nothing sampled):
  std::uint64_t attack_switches = 0;    // the attack direction changed (ends changed)
  std::uint64_t opponent_switches = 0;  // the opponent's colour changed (set_opponent)
  std::uint64_t transitions = 0;
};

// "non_finite=0 out_of_range=0 ..." : every refusal counter, zeros too.
std::string describe_rejections(const SamplerCounters& counters);
// Every refusal counter with the name status lines give it ("non_finite", "late", ...), in the
// order they print them.
std::vector<std::pair<std::string_view, std::uint64_t>> rejection_counts(
    const SamplerCounters& counters);
// One sentence per kind of refusal that grew from `before` to `after` ("2 frames with a camera id
// over the limit (5 in all)"), for a daemon to log as warnings when new kinds of bad input arrive.
std::vector<std::string> new_rejections(const SamplerCounters& before,
                                        const SamplerCounters& after);

// Frame sampling's history: formations oldest first, in a ring of slots that keep their storage.
// A formation joins by swapping with a free slot, so a steady stream neither allocates (a deque
// allocates and frees a block every few formations) nor copies robots.
class FormationHistory {
 public:
  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  const Formation& operator[](std::size_t i) const { return slots_[slot(i)]; }
  const Formation& front() const { return slots_[head_]; }
  const Formation& back() const { return slots_[slot(size_ - 1)]; }
  void pop_front() {
    head_ = slot(1);
    --size_;
  }
  void clear() {
    head_ = 0;
    size_ = 0;
  }
  // `formation` becomes the newest and gets the storage of the slot it takes.
  void push_back_swap(Formation& formation);

 private:
  std::size_t slot(std::size_t i) const {
    const std::size_t at = head_ + i;
    return at < slots_.size() ? at : at - slots_.size();
  }
  std::vector<Formation> slots_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

class FormationSampler : private DataClockListener {
 public:
  using SampleHandler = std::function<void(const FormationSample&)>;

  // Throws std::invalid_argument for a step that is not positive and finite.
  FormationSampler(SamplerConfig config, SampleHandler on_sample);

  // Feeds one packet; calls the handler for every sample it completes (zero, one or two).
  void add(const VisionFrame& frame);
  void add(const SSL_WrapperPacket& packet);

  // Forgets the stream so far (cameras, clock, previous formation) but keeps the field size and
  // the counters: the next packet starts a new stream, and no transition spans the two.
  void start_new_stream();

  // The opponent changed while the stream goes on (the referee names another team, or the
  // teams changed ends). Another colour forgets the robots seen so far; another side breaks the
  // chain, as an inferred change of ends does (cells on either side do not compare). `attacks`
  // none: inferred from where the goalkeeper stands from here on. Nothing happens when both are
  // as they were.
  void set_opponent(TeamColor color, std::optional<AttackDirection> attacks);
  // No transition spans this point (the referee issued a new command, and learning in running
  // play keeps the states apart). Counted as a chain break.
  void start_new_segment() { break_chain(); }

  const SamplerConfig& config() const { return config_; }
  const StateCodec& codec() const { return codec_; }
  const FieldSize& field() const { return field_; }
  // The direction the opponent attacks now: the configured one, or the inferred one (see
  // infer_attacks; nothing before the first inference).
  std::optional<AttackDirection> attacks() const { return attacks_; }
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
    bool in_instant = false;  // already in an instant (FormationRobot::observed false after)
  };

  void add_geometry(std::int32_t field_length, std::int32_t field_width);
  void add_detection(const VisionDetection& frame);
  // What the data clock reports (DataClockListener).
  void on_frame(const ClockFrame& frame, const std::vector<FrameDetection>& detections) override;
  void on_instant(const ClockInstant& instant) override;
  void on_restart(ClockRestart why) override;
  void on_event(ClockEvent event) override;
  // Forgets the robots and the previous formation (the clock forgets its own part).
  void forget_stream();
  // Forgets the formations a later one could take its previous cells from (a chain break).
  void break_chain();
  void on_frame_instant(const ClockInstant& instant, std::vector<FormationRobot>& robots);
  FormationSample& build_sample(const ClockInstant& instant, std::vector<FormationRobot>& robots,
                                const Formation* before, const Formation* latest);

  SamplerConfig config_;
  StateCodec codec_;
  DataClock clock_;
  SampleHandler on_sample_;
  FieldSize field_;
  SamplerCounters counters_;
  std::optional<AttackDirection> attacks_;
  AttackInference attack_inference_;
  std::vector<AttackInference::Robot> inference_scratch_;

  VisionFrame packet_scratch_;  // add(SSL_WrapperPacket) converts into this
  std::vector<FrameDetection> frame_scratch_;
  std::vector<Observation> observations_;    // indexed by robot id
  std::vector<std::uint32_t> observed_ids_;  // ids with an observation, sorted
  std::uint32_t last_frame_number_ = 0;      // of the last frame used

  // Step sampling: the last sample and its instant number.
  std::optional<Formation> previous_;
  std::int64_t previous_k_ = 0;
  // Frame sampling: the samples of the last step (and the tolerance), oldest first.
  FormationHistory history_;
  std::uint64_t restarts_ = 0;  // calls of forget_stream(), so a sample sees one by its handler
  // Reused from sample to sample, so that a steady stream allocates nothing.
  std::vector<FormationRobot> robots_scratch_;
  FormationSample sample_scratch_;
};

}  // namespace vision
}  // namespace ssl_formation
