#pragma once
// The paper's §6 protocol, and the scores every evaluation keeps: accuracy on cells and the
// calibration of a stated probability. Pure: tables, formations and numbers in, numbers out.

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/model_api/transition_table.hpp"
#include "ssl_formation/paper_model/predictor.hpp"

namespace ssl_formation::evaluation {

// ---- Paper protocol (§6.1) -------------------------------------------------------------------

// A reference play: its formations as robot states (formation 0 with velocity 0, each next one
// with the previous formation's cells as previous cells), built from positions.
using PlayStates = std::vector<std::vector<RobotStateById>>;
PlayStates play_states(const StateCodec& codec, const FieldSize& field,
                       const std::vector<std::vector<Point>>& play_positions);

struct PaperTest {
  int count_play = 0;                  // the play chosen by the count measure of formation 1
  int distance_play = 0;               // the play chosen by the distance measure of formation 1
  std::array<int, 3> count{};          // per formation 1-3, against count_play
  std::array<int, 3> distance{};       // per formation 1-3, against distance_play
  std::array<double, 2> confidence{};  // of the 1st and 2nd predicted formation
};

// One test: a formation (velocity 0) and its two predicted successors, compared with the play
// whose first formation is closest under each measure (ties: the lowest play number).
PaperTest run_paper_test(const TransitionTable& table, const std::vector<RobotStateById>& formation,
                         const std::vector<PlayStates>& plays);

struct PaperSummary {
  int tests = 0;
  double count_per_play = 0;  // mean over tests of the sum over formations 1-3
  double distance_per_play = 0;
  double count_per_formation = 0;  // the above / 3
  double distance_per_formation = 0;
  std::array<double, 2> mean_confidence{};
};
void accumulate(PaperSummary& summary, const PaperTest& test);  // running means

// ---- Scores shared by every evaluation -----------------------------------------------------

struct Accuracy {
  std::uint64_t formations = 0;
  std::uint64_t robots = 0;
  std::uint64_t exact_states = 0;   // predicted state == actual state
  std::uint64_t exact_cells = 0;    // predicted position cell == actual
  std::uint64_t cell_distance = 0;  // Manhattan, in cells, summed over robots
  double state_accuracy() const { return robots ? double(exact_states) / double(robots) : 0.0; }
  double cell_accuracy() const { return robots ? double(exact_cells) / double(robots) : 0.0; }
  double mean_distance() const { return robots ? double(cell_distance) / double(robots) : 0.0; }
};
void score(Accuracy& accuracy, const StateCodec& codec,
           const std::vector<RobotStateById>& predicted, const std::vector<RobotStateById>& actual);

// Calibration of a probability against 0/1 outcomes: Brier score and a reliability table.
struct Calibration {
  static constexpr int bins = 10;
  std::uint64_t n = 0;
  double squared_error = 0;
  std::array<std::uint64_t, bins> bin_count{};
  std::array<double, bins> bin_confidence{};  // sum of confidences in the bin
  std::array<std::uint64_t, bins> bin_hits{};

  void add(double confidence, bool outcome);
  double brier() const { return n ? squared_error / double(n) : 0.0; }
  // Bin b holds confidences in [b/10, (b+1)/10), the last one also 1.0.
  static int bin_of(double confidence);
};

}  // namespace ssl_formation::evaluation
