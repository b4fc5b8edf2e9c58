#pragma once
// What a team's AI links to read ssl-predictor's predictions: receives the FormationPrediction
// datagrams on the prediction group and hands them over as plain structs, so that the team's
// code needs neither our .proto nor a protobuf include of its own (only the library links
// protobuf). Installed with the programs; a CMake project uses it through
//   find_package(ssl_formation REQUIRED)
//   target_link_libraries(my_ai PRIVATE sslf::client)

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace ssl_formation::client {

// One robot of the opponent, one step ahead.
struct PredictedRobot {
  std::uint32_t robot_id = 0;
  // Where it is predicted, mm in the vision feed's coordinates: the motion model's position, or
  // the predicted cell's centre for the paper's model (has_radii false then).
  double x_mm = 0.0, y_mm = 0.0;
  // Circles about (x_mm, y_mm) holding the robot with 50% and 90% probability.
  bool has_radii = false;
  double radius_50_mm = 0.0, radius_90_mm = 0.0;
  double probability = 0.0;  // that its predicted cell is right
  bool unseen = false;       // the robot was not seen in the frame predicted from
};

struct PredictedStep {
  int step = 0;            // 1, 2, ... steps of step_s ahead
  double horizon_s = 0.0;  // seconds ahead of t_capture
  double formation_probability = 0.0;
  std::vector<PredictedRobot> robots;
};

struct Prediction {
  std::uint32_t frame_number = 0;
  double t_capture = 0.0;  // the frame's capture time, s (the vision feed's clock)
  std::string model;       // "motion", "paper" or a baseline's name; empty if not said
  std::string game_state;  // the referee's state the prediction was made in; empty if none
  std::string opponent_color;
  int grid_length = 0, grid_width = 0;  // 0: not said
  double step_s = 0.0;
  std::vector<PredictedStep> steps;
};

// A FormationPrediction datagram as plain structs; none for bytes that are not one.
std::optional<Prediction> decode_prediction(const void* data, std::size_t size);

// The prediction group joined on one interface. Blocking reads with a timeout; one thread.
class PredictionReceiver {
 public:
  // `group`: "address:port" as ssl-predictor's --prediction-address (224.5.23.4:10040 by
  // default); `interface`: the address of the interface to join on (127.0.0.1 when the
  // predictor runs on this machine). Throws std::runtime_error saying what failed.
  explicit PredictionReceiver(const std::string& group = "224.5.23.4:10040",
                              const std::string& interface = "127.0.0.1");
  ~PredictionReceiver();
  PredictionReceiver(const PredictionReceiver&) = delete;
  PredictionReceiver& operator=(const PredictionReceiver&) = delete;

  // The next prediction, waiting at most `timeout`; none when none came. Datagrams that are not
  // predictions are skipped and counted.
  std::optional<Prediction> receive(std::chrono::milliseconds timeout);
  std::uint64_t undecodable() const { return undecodable_; }

 private:
  int socket_ = -1;
  std::vector<std::byte> buffer_;
  std::uint64_t undecodable_ = 0;
};

}  // namespace ssl_formation::client
