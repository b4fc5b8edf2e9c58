#pragma once
// One held-out evaluation as it runs (Evaluation): the methods it trains, their pipelines on the
// test streams, and the instants waiting for their truth. Driven by evaluate_positions
// (position_evaluation.cpp); its steps are in held_out_run.cpp.

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "ssl_formation/evaluation/position_evaluation.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"

namespace ssl_formation::evaluation::detail {

inline double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }

// Index of the entry of `items` (sorted by time) nearest `time_s`, if within `tolerance_s`.
template <typename Items, typename TimeOf>
std::optional<std::size_t> nearest_index(const Items& items, double time_s, double tolerance_s,
                                         TimeOf time_of) {
  if (items.empty()) return std::nullopt;
  const auto after =
      std::lower_bound(items.begin(), items.end(), time_s,
                       [&](const auto& item, double t) { return time_of(item) < t; });
  std::optional<std::size_t> best;
  double best_gap = tolerance_s;
  const auto consider = [&](auto it) {
    const double gap = std::abs(time_of(*it) - time_s);
    if (gap <= best_gap) {
      best_gap = gap;
      best = static_cast<std::size_t>(it - items.begin());
    }
  };
  if (after != items.begin()) consider(after - 1);  // the earlier wins a tie
  if (after != items.end()) consider(after);
  return best;
}

// One method's predictions at one instant of a test stream.
struct Instant {
  double time_s = 0.0;
  GamePhase phase = GamePhase::running;
  std::vector<PredictedStep> steps;
};

// The model's prediction at an instant with the formation it was sampled from: the truth of the
// predictions made before it.
struct ModelInstant {
  Instant instant;
  Formation formation;
};

inline double model_time(const ModelInstant& x) { return x.formation.time_s; }
inline double instant_time(const Instant& x) { return x.time_s; }

inline const RobotPrediction* find_robot(const PredictedStep& step, std::uint32_t robot_id) {
  const auto it = std::find_if(step.robots.begin(), step.robots.end(),
                               [&](const RobotPrediction& r) { return r.robot_id == robot_id; });
  return it == step.robots.end() ? nullptr : &*it;
}

// How long, in data time, an instant waits for a method that has predicted nothing at or after
// it. Every front end reads the same events, so a method lags the model by a frame or two at
// most: one that is further behind predicted nothing there, and waiting longer would only let
// the instants kept grow.
constexpr double wait_limit_s = 10.0;

// A method as the evaluation runs it: its sampling, what it learned, its pipeline on the test
// streams and the predictions it made there that may still be a model instant's nearest.
struct Method {
  ModelKind kind;
  PredictionConfig prediction;
  std::unique_ptr<Training> training;            // until the test streams begin
  std::unique_ptr<PredictionPipeline> pipeline;  // from then on
  std::deque<Instant> waiting;                   // the baselines' (the model's: Evaluation::model_)
  // Where in `waiting` the method's clock went back, since the last event.
  std::optional<std::size_t> went_back_at;
  ModelSettings settings;  // what its learner and forecaster are made with
};

// A configuration's front ends, one per sampling: its methods differ in nothing else that a
// front end reads (the baselines that need every frame sample every frame where the model may
// sample every step), so each message is parsed once per sampling rather than once per method.
class FrontEnds final : public MatchEventSink {
 public:
  MatchFrontEnd& of(const FrontEndConfig& config) {
    for (const auto& front_end : front_ends_) {
      if (front_end->config().sampler.sampling == config.sampler.sampling) return *front_end;
    }
    front_ends_.push_back(std::make_unique<MatchFrontEnd>(config, MatchFrontEnd::Handlers{}));
    return *front_ends_.back();
  }
  void on_event(const MatchEvent& event) override {
    for (const auto& front_end : front_ends_) front_end->on_event(event);
  }
  void start_new_stream() override {
    for (const auto& front_end : front_ends_) front_end->start_new_stream();
  }
  void clear() { front_ends_.clear(); }

 private:
  std::vector<std::unique_ptr<MatchFrontEnd>> front_ends_;
};

// One configuration evaluated as the streams go by: its methods trained on the training streams,
// then each test stream's predictions scored as soon as the truth of their last horizon is in,
// so that what is kept spans a few seconds of data, never a whole stream.
class Evaluation {
 public:
  explicit Evaluation(const PositionEvaluationConfig& config);
  Evaluation(const Evaluation&) = delete;
  Evaluation& operator=(const Evaluation&) = delete;

  MatchEventSink& training() { return training_front_ends_; }
  // What was learned, handed to the methods' forecasters; the training is let go.
  void end_training();
  void start_test_stream(std::size_t stream);
  void on_test_event(const MatchEvent& event);
  void end_test_stream();
  PositionEvaluation finish();

 private:
  void on_prediction(std::size_t m, const PredictedFormation& p);
  // Scores every model instant whose predictions and truths are all in (every one at a stream's
  // end), and lets go of what no later instant can need.
  void score_ready(bool ended);
  bool ready(double time_s) const;
  // Scores the oldest model instant and every method's prediction at its nearest instant, at
  // every horizon, into the rows "all" and the instant's phase.
  void score_front();
  void drop_stale();

  const PositionEvaluationConfig& config_;
  PositionEvaluation result_;
  std::vector<Method> methods_;
  FrontEnds training_front_ends_;
  FrontEnds test_front_ends_;
  std::deque<ModelInstant> model_;
  std::optional<std::size_t> model_went_back_at_;
  std::size_t stream_ = 0;
  // Of the current test stream: the newest instant any method predicted at, and the model's.
  double newest_s_ = -std::numeric_limits<double>::infinity();
  double newest_model_s_ = -std::numeric_limits<double>::infinity();
};

}  // namespace ssl_formation::evaluation::detail
