#pragma once
// The ball as the raw vision shows it, followed across cameras: where it was seen last and how
// fast it moves. Per detection frame the camera's most confident ball counts; the newest
// sighting of any camera is the ball (two overlapping cameras at one instant are averaged, as
// the sampler does for robots); a jump of metres, or a ball unseen for a while, starts over.
//
// Why a least-squares line over a short window and not RobotTracker's filter: a ball changes
// speed in one frame (a kick, a bounce off a robot), and a straight line over the last 0.1 s
// forgets the old speed within the window while averaging the vision's few millimetres of noise.
// The line is fitted within each camera (the slope shared, an offset per camera): overlapping
// cameras disagree by a few centimetres where their calibrations meet, and two sightings of one
// instant from two cameras must not read as a ball moving metres a second.
//
// Pure: time is the data clock (t_capture), handed in with every sighting.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/vision/vision_frame.hpp"

namespace ssl_formation {
inline namespace vision {

struct BallTrackerSettings {
  // Ball candidates below this confidence are left out. SSL-Vision rates every orange blob by how
  // ball-like it is and already drops the worst; grSim sends its ball at 0.9 to 1. A low floor
  // leaves that judgement to the vision and only drops what it barely believed itself (and a
  // sender's zeros); among the rest, each frame's most confident ball counts.
  float min_confidence = 0.1F;
  // The velocity is the slope of a line through the sightings of this last stretch of time: at
  // 60 Hz seven frames, whose slope has about 35 mm/s of noise under 3 mm of vision noise (two
  // frames' difference would have 250).
  double velocity_window_s = 0.1;
  // A ball unseen for this long is gone (off the field, in a robot's hands, covered); its next
  // sighting starts over, and at() says nothing of it.
  double forget_after_s = 0.5;
  // A sighting farther from the last than jump_mm plus max_speed_mm_s times the time between
  // them is another ball (a second ball, one put down elsewhere, a ghost): the follower starts
  // over from it. A kicked ball moves at most 6.5 m/s by the rules.
  double jump_mm = 1000.0;
  double max_speed_mm_s = 8000.0;
  // Sightings this close in time are one instant (overlapping cameras' frames of one exposure).
  double same_instant_s = 0.001;
  // Coordinates beyond this are nonsense, as the sampler's max_abs_coordinate_mm.
  double max_abs_coordinate_mm = 100000.0;
  // The most sightings the window keeps (8 cameras at 100 Hz over 0.1 s are 80).
  std::size_t max_window_sightings = 256;
  bool valid() const;
};

// The ball as followed, in feed coordinates.
struct BallState {
  double time_s = 0.0;  // the data clock of its newest sighting
  Point position;       // millimetres
  Point velocity;       // millimetres per second; zero until two sightings give one
};

class BallTracker {
 public:
  // Throws std::invalid_argument for settings that are not valid().
  explicit BallTracker(BallTrackerSettings settings = {});

  // A raw detection frame: its most confident ball above the floor, if any, is a sighting by its
  // camera at its t_capture. Frames without a usable ball change nothing.
  void add(const VisionDetection& detection);
  // One sighting of the ball by `camera_id` at `time_s` (the data clock). One older than the
  // newest (a slower camera's frame, or one out of order) only joins the velocity's window; one
  // more than forget_after_s older than it is another clock, and starts over.
  void observe(double time_s, Point position, std::uint32_t camera_id);
  // A tracker's estimate (tracked vision), taken as it is: it replaces what was followed.
  void set(const BallState& state);

  // Forgets the ball (a new stream).
  void reset();

  // The ball as last seen; none before the first sighting (or after reset()).
  const std::optional<BallState>& state() const { return state_; }
  // The ball at data time `time_s`: none if it was not seen within forget_after_s of it.
  std::optional<BallState> at(double time_s) const;
  const BallTrackerSettings& settings() const { return settings_; }

 private:
  struct Sighting {
    double time_s = 0.0;
    Point position;
    std::uint32_t camera_id = 0;
  };
  // Per camera, sums over the window's sightings (times relative to the newest).
  struct CameraSums {
    std::uint32_t camera_id = 0;
    double n = 0.0, t = 0.0, x = 0.0, y = 0.0, tt = 0.0, tx = 0.0, ty = 0.0;
    double first_s = 0.0, last_s = 0.0;
  };

  void start_over(double time_s, Point position, std::uint32_t camera_id);
  void update_velocity();

  BallTrackerSettings settings_;
  std::optional<BallState> state_;
  // The newest instant's sightings, averaged across cameras.
  double instant_sum_x_ = 0.0;
  double instant_sum_y_ = 0.0;
  double instant_weight_ = 0.0;
  // The velocity's window, oldest mostly first; both vectors keep their capacity.
  std::vector<Sighting> window_;
  std::vector<CameraSums> sums_scratch_;
};

}  // namespace vision
}  // namespace ssl_formation
