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

const char* to_string(Method method) {
  switch (method) {
    case Method::model:
      return "model";
    case Method::persistence:
      return "persistence";
    case Method::constant_velocity:
      return "constant velocity";
  }
  return "?";
}

std::vector<RobotStateById> persistence(const StateCodec& codec, const Formation& current) {
  const StateIndex centroid = static_cast<StateIndex>(codec.grid().cell_id(current.centroid_cell));
  std::vector<RobotStateById> out;
  out.reserve(current.robots.size());
  for (const FormationRobot& robot : current.robots) {
    const StateIndex cell = static_cast<StateIndex>(codec.grid().cell_id(robot.cell));
    out.push_back({robot.robot_id, codec.compose(centroid, cell, cell)});
  }
  return out;
}

std::vector<RobotStateById> constant_velocity(const StateCodec& codec, const FieldSize& field,
                                              const Formation& current, int horizon) {
  const Grid& grid = codec.grid();
  const auto moved = [&](const FormationRobot& robot, int steps) {
    const Cell v = Cell{robot.cell.x - robot.previous_cell.x, robot.cell.y - robot.previous_cell.y};
    return Cell{std::clamp(robot.cell.x + steps * v.x, 0, grid.length() - 1),
                std::clamp(robot.cell.y + steps * v.y, 0, grid.width() - 1)};
  };
  Point sum;
  for (const FormationRobot& robot : current.robots) {
    const Point centre = grid.centre_of(moved(robot, horizon), field);
    sum.x += centre.x;
    sum.y += centre.y;
  }
  const double n = static_cast<double>(std::max<std::size_t>(current.robots.size(), 1));
  const Cell centroid = grid.cell_of(Point{sum.x / n, sum.y / n}, field);
  std::vector<RobotStateById> out;
  out.reserve(current.robots.size());
  for (const FormationRobot& robot : current.robots) {
    out.push_back({robot.robot_id,
                   codec.encode({centroid, moved(robot, horizon), moved(robot, horizon - 1)})});
  }
  return out;
}

std::vector<RobotStateById> predict_with(Method method, const TransitionTable& table,
                                         const Formation& current, int horizon,
                                         const FieldSize& field, double* confidence) {
  switch (method) {
    case Method::persistence:
      return persistence(table.codec(), current);
    case Method::constant_velocity:
      return constant_velocity(table.codec(), field, current, horizon);
    case Method::model:
      break;
  }
  Prediction prediction;
  predict(table, robot_states(current), horizon, prediction);
  if (prediction.steps.empty()) return {};
  const PredictedStep& last = prediction.steps.back();
  if (confidence) *confidence = last.confidence;
  return robot_states(last);
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

HoldoutResult evaluate_holdout(const StateCodec& codec, const std::vector<PredictedTest>& test,
                               const FieldSize& field) {
  HoldoutResult result;
  for (std::size_t i = 0; i < test.size(); ++i) {
    const Formation& current = test[i].formation;
    for (int horizon = 1; horizon <= HoldoutResult::max_horizon; ++horizon) {
      const std::size_t target = i + static_cast<std::size_t>(horizon);
      if (target >= test.size() || !test[target].formation.continues_previous) break;
      const std::vector<RobotStateById> actual = robot_states(test[target].formation);
      const auto h = static_cast<std::size_t>(horizon - 1);
      for (std::size_t m = 0; m < all_methods.size(); ++m) {
        std::vector<RobotStateById> predicted;
        double confidence = 0.0;
        switch (all_methods[m]) {
          case Method::persistence:
            predicted = persistence(codec, current);
            break;
          case Method::constant_velocity:
            predicted = constant_velocity(codec, field, current, horizon);
            break;
          case Method::model:
            if (h < test[i].prediction.steps.size()) {
              const PredictedStep& step = test[i].prediction.steps[h];
              predicted = robot_states(step);
              confidence = step.confidence;
            }
            break;
        }
        Accuracy& accuracy = result.accuracy[h][m];
        const std::uint64_t exact_before = accuracy.exact_states;
        score(accuracy, codec, predicted, actual);
        if (all_methods[m] == Method::model) {
          const bool all_right = accuracy.exact_states - exact_before == actual.size() &&
                                 predicted.size() == actual.size();
          result.calibration[h].add(confidence, all_right);
        }
      }
    }
  }
  return result;
}

HoldoutResult evaluate_holdout(const TransitionTable& table, const std::vector<Formation>& test,
                               const FieldSize& field) {
  std::vector<PredictedTest> predicted;
  predicted.reserve(test.size());
  for (const Formation& formation : test) {
    predicted.push_back({formation, predict(table, formation, HoldoutResult::max_horizon)});
  }
  return evaluate_holdout(table.codec(), predicted, field);
}

}  // namespace ssl_formation::evaluation
