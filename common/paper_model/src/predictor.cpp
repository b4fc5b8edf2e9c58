#include "ssl_formation/paper_model/predictor.hpp"

namespace ssl_formation {
inline namespace paper_model {

namespace {

// Writes step `out` from the states in `from`, which all share one centroid.
template <class Robots, class StateOf>
void predict_step(const TransitionTable& table, const Robots& from, StateOf state_of,
                  double base_confidence, PredictedStep& out) {
  const StateCodec& codec = table.codec();
  const Grid& grid = codec.grid();
  const StateIndex cells = codec.cell_count();
  const double unseen_probability = 1.0 / static_cast<double>(cells);

  const StateIndex centroid = codec.centroid_id(state_of(from.front()));
  const std::uint64_t centroid_total = table.centroid_total(centroid);
  StateIndex next_centroid = centroid;
  if (centroid_total == 0) {
    out.centroid_probability = unseen_probability;
    out.centroid_unseen = true;
  } else {
    std::uint64_t best = 0;
    for (StateIndex c = 0; c < cells; ++c) {
      const std::uint64_t count = table.centroid_count(centroid, c);
      if (count > best) {  // strict: ties keep the lowest index
        best = count;
        next_centroid = c;
      }
    }
    out.centroid_probability = static_cast<double>(best) / static_cast<double>(centroid_total);
    out.centroid_unseen = false;
  }
  out.centroid = grid.cell_from_id(static_cast<int>(next_centroid));

  double formation_probability = out.centroid_probability;
  out.robots.resize(from.size());
  for (std::size_t i = 0; i < from.size(); ++i) {
    const StateIndex state = state_of(from[i]);
    const StateIndex position = codec.position_id(state);
    const auto best = table.best_successor(state, next_centroid, position);
    RobotPrediction& robot = out.robots[i];
    robot.robot_id = from[i].robot_id;
    if (best.candidates_total == 0) {
      robot.state = codec.compose(next_centroid, position, position);
      robot.probability = unseen_probability;
      robot.unseen = true;
    } else {
      robot.state = best.state;
      robot.probability =
          static_cast<double>(best.best_count) / static_cast<double>(best.candidates_total);
      robot.unseen = false;
    }
    robot.position = grid.cell_from_id(static_cast<int>(codec.position_id(robot.state)));
    robot.previous = grid.cell_from_id(static_cast<int>(codec.previous_id(robot.state)));
    formation_probability *= robot.probability;
  }
  out.formation_probability = formation_probability;
  out.confidence = base_confidence * formation_probability;
}

}  // namespace

void predict(const TransitionTable& table, const std::vector<RobotStateById>& robots, int horizon,
             Prediction& out) {
  const std::size_t steps = robots.empty() || horizon < 1 ? 0 : static_cast<std::size_t>(horizon);
  out.steps.resize(steps);
  for (std::size_t k = 0; k < steps; ++k) {
    if (k == 0) {
      predict_step(
          table, robots, [](const RobotStateById& r) { return r.state; }, 1.0, out.steps[0]);
    } else {
      // The predicted formation is the base of the next step (paper §5.2).
      const PredictedStep& base = out.steps[k - 1];
      predict_step(
          table, base.robots, [](const RobotPrediction& r) { return r.state; }, base.confidence,
          out.steps[k]);
    }
  }
}

Prediction predict(const TransitionTable& table, const Formation& formation, int horizon) {
  Prediction prediction;
  predict(table, robot_states(formation), horizon, prediction);
  return prediction;
}

std::vector<RobotStateById> robot_states(const Formation& formation) {
  std::vector<RobotStateById> robots;
  robots.reserve(formation.robots.size());
  for (const FormationRobot& robot : formation.robots)
    robots.push_back({robot.robot_id, robot.state});
  return robots;
}

std::vector<RobotStateById> robot_states(const PredictedStep& step) {
  std::vector<RobotStateById> robots;
  robots.reserve(step.robots.size());
  for (const RobotPrediction& robot : step.robots) robots.push_back({robot.robot_id, robot.state});
  return robots;
}

}  // namespace paper_model
}  // namespace ssl_formation
