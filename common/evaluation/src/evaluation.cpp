#include "ssl_formation/evaluation/evaluation.hpp"

#include <algorithm>
#include <cmath>

#include "ssl_formation/paper_model/measures.hpp"
#include "ssl_formation/vision/sampler.hpp"

namespace ssl_formation::evaluation {

PlayStates play_states(const StateCodec& codec, const FieldSize& field,
                       const std::vector<std::vector<Point>>& play_positions) {
  PlayStates states;
  std::optional<Formation> previous;
  for (const std::vector<Point>& positions : play_positions) {
    Formation formation =
        FormationSampler::formation_at(codec, field, positions, previous ? &*previous : nullptr);
    states.push_back(robot_states(formation));
    previous = std::move(formation);
  }
  return states;
}

namespace {

// The play whose first formation is closest to `formation` under `measure`; ties: lowest play.
template <class Measure>
int closest_play(const std::vector<RobotStateById>& formation, const std::vector<PlayStates>& plays,
                 Measure measure) {
  int best = 0;
  int best_value = 0;
  for (std::size_t p = 0; p < plays.size(); ++p) {
    const int value = measure(formation, plays[p][0]);
    if (p == 0 || value < best_value) {
      best = static_cast<int>(p);
      best_value = value;
    }
  }
  return best;
}

}  // namespace

PaperTest run_paper_test(const TransitionTable& table, const std::vector<RobotStateById>& formation,
                         const std::vector<PlayStates>& plays) {
  const StateCodec& codec = table.codec();
  Prediction prediction;
  predict(table, formation, 2, prediction);
  const std::array<std::vector<RobotStateById>, 3> ours{
      formation, robot_states(prediction.steps[0]), robot_states(prediction.steps[1])};

  PaperTest test;
  const auto count = [](const auto& a, const auto& b) { return count_measure(a, b); };
  const auto distance = [&](const auto& a, const auto& b) { return distance_measure(codec, a, b); };
  test.count_play = closest_play(formation, plays, count);
  test.distance_play = closest_play(formation, plays, distance);
  for (std::size_t f = 0; f < 3; ++f) {
    test.count[f] = count(ours[f], plays[static_cast<std::size_t>(test.count_play)][f]);
    test.distance[f] = distance(ours[f], plays[static_cast<std::size_t>(test.distance_play)][f]);
  }
  test.confidence = {prediction.steps[0].confidence, prediction.steps[1].confidence};
  return test;
}

void accumulate(PaperSummary& summary, const PaperTest& test) {
  const double n = ++summary.tests;
  const auto running = [n](double& mean, double value) { mean += (value - mean) / n; };
  running(summary.count_per_play, test.count[0] + test.count[1] + test.count[2]);
  running(summary.distance_per_play, test.distance[0] + test.distance[1] + test.distance[2]);
  summary.count_per_formation = summary.count_per_play / 3.0;
  summary.distance_per_formation = summary.distance_per_play / 3.0;
  running(summary.mean_confidence[0], test.confidence[0]);
  running(summary.mean_confidence[1], test.confidence[1]);
}

void score(Accuracy& accuracy, const StateCodec& codec,
           const std::vector<RobotStateById>& predicted,
           const std::vector<RobotStateById>& actual) {
  ++accuracy.formations;
  const Grid& grid = codec.grid();
  for (const RobotStateById& truth : actual) {
    ++accuracy.robots;
    const auto guess =
        std::find_if(predicted.begin(), predicted.end(),
                     [&](const RobotStateById& r) { return r.robot_id == truth.robot_id; });
    if (guess == predicted.end()) continue;  // a robot the method could not know of: wrong
    if (guess->state == truth.state) ++accuracy.exact_states;
    const Cell a = grid.cell_from_id(static_cast<int>(codec.position_id(guess->state)));
    const Cell b = grid.cell_from_id(static_cast<int>(codec.position_id(truth.state)));
    if (a == b) ++accuracy.exact_cells;
    accuracy.cell_distance += static_cast<std::uint64_t>(std::abs(a.x - b.x) + std::abs(a.y - b.y));
  }
}

int Calibration::bin_of(double confidence) {
  const int bin = static_cast<int>(std::floor(confidence * bins));
  return std::clamp(bin, 0, bins - 1);
}

void Calibration::add(double confidence, bool outcome) {
  ++n;
  const double target = outcome ? 1.0 : 0.0;
  squared_error += (confidence - target) * (confidence - target);
  const auto b = static_cast<std::size_t>(bin_of(confidence));
  ++bin_count[b];
  bin_confidence[b] += confidence;
  if (outcome) ++bin_hits[b];
}

}  // namespace ssl_formation::evaluation
