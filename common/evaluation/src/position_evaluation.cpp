#include "ssl_formation/evaluation/position_evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>

#include "held_out_run.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"

namespace ssl_formation::evaluation {

using detail::Evaluation;
using detail::nearest_index;

std::string_view state_row_name(std::size_t row) {
  return row == 0 ? std::string_view("all") : to_string(all_game_phases[row - 1]);
}

std::vector<std::size_t> PositionEvaluation::reported_rows() const {
  if (!test_has_referee) return {0, state_row_of(GamePhase::running)};
  std::vector<std::size_t> all_rows(state_rows);
  for (std::size_t r = 0; r < all_rows.size(); ++r) all_rows[r] = r;
  return all_rows;
}

std::optional<std::size_t> best_baseline(const HorizonScore& score, std::size_t baselines_end) {
  std::optional<std::size_t> best;
  for (std::size_t m = 1; m < std::min(baselines_end, score.methods.size()); ++m) {
    if (score.methods[m].error.count() == 0) continue;
    if (!best || score.methods[m].error.mean() < score.methods[*best].error.mean()) best = m;
  }
  return best;
}

const Formation* formation_near(const std::vector<Formation>& formations, double time_s,
                                double tolerance_s) {
  const auto index =
      nearest_index(formations, time_s, tolerance_s, [](const Formation& f) { return f.time_s; });
  return index ? &formations[*index] : nullptr;
}

EventStream replay_of(const RecordedMatch& match) {
  return [&match](MatchEventSink& sink) { match.replay(sink); };
}

namespace {

// Hands every event to each of `sinks`, in order.
class FanOut final : public MatchEventSink {
 public:
  explicit FanOut(std::vector<MatchEventSink*> sinks) : sinks_(std::move(sinks)) {}
  void on_event(const MatchEvent& event) override {
    for (MatchEventSink* sink : sinks_) sink->on_event(event);
  }
  void start_new_stream() override {
    for (MatchEventSink* sink : sinks_) sink->start_new_stream();
  }

 private:
  std::vector<MatchEventSink*> sinks_;
};

// The test streams' events for one evaluation: scored as they go.
class TestSink final : public MatchEventSink {
 public:
  explicit TestSink(Evaluation& evaluation) : evaluation_(evaluation) {}
  void on_event(const MatchEvent& event) override { evaluation_.on_test_event(event); }
  void start_new_stream() override {}  // Evaluation::start_test_stream, with the stream's number

 private:
  Evaluation& evaluation_;
};

}  // namespace

std::vector<PositionEvaluation> evaluate_positions(
    const std::vector<PositionEvaluationConfig>& configs, const std::vector<EventStream>& train,
    const std::vector<EventStream>& test) {
  for (const PositionEvaluationConfig& config : configs) {
    if (config.recorded_predictions && test.size() != 1) {
      throw std::invalid_argument("recorded predictions are scored against one test stream");
    }
  }
  std::vector<std::unique_ptr<Evaluation>> evaluations;
  std::vector<MatchEventSink*> training;
  std::vector<std::unique_ptr<TestSink>> test_sinks;
  std::vector<MatchEventSink*> testing;
  for (const PositionEvaluationConfig& config : configs) {
    evaluations.push_back(std::make_unique<Evaluation>(config));
    training.push_back(&evaluations.back()->training());
    test_sinks.push_back(std::make_unique<TestSink>(*evaluations.back()));
    testing.push_back(test_sinks.back().get());
  }
  // Each stream is read once, for every configuration.
  FanOut train_fan(std::move(training));
  for (const EventStream& stream : train) {
    train_fan.start_new_stream();
    stream(train_fan);
  }
  for (const auto& evaluation : evaluations) evaluation->end_training();
  FanOut test_fan(std::move(testing));
  for (std::size_t t = 0; t < test.size(); ++t) {
    for (const auto& evaluation : evaluations) evaluation->start_test_stream(t);
    test[t](test_fan);
    for (const auto& evaluation : evaluations) evaluation->end_test_stream();
  }
  std::vector<PositionEvaluation> results;
  for (const auto& evaluation : evaluations) results.push_back(evaluation->finish());
  return results;
}

PositionEvaluation evaluate_positions(const PositionEvaluationConfig& config,
                                      const std::vector<RecordedMatch>& train,
                                      const std::vector<RecordedMatch>& test) {
  std::vector<EventStream> train_streams;
  for (const RecordedMatch& match : train) train_streams.push_back(replay_of(match));
  std::vector<EventStream> test_streams;
  for (const RecordedMatch& match : test) test_streams.push_back(replay_of(match));
  return std::move(evaluate_positions({config}, train_streams, test_streams).front());
}

double expected_calibration_error(const Calibration& calibration) {
  if (calibration.n == 0) return 0.0;
  double sum = 0.0;
  for (std::size_t b = 0; b < calibration.bin_count.size(); ++b) {
    const std::uint64_t count = calibration.bin_count[b];
    if (count == 0) continue;
    const double observed =
        static_cast<double>(calibration.bin_hits[b]) / static_cast<double>(count);
    const double confidence = calibration.bin_confidence[b] / static_cast<double>(count);
    sum += static_cast<double>(count) * std::abs(observed - confidence);
  }
  return sum / static_cast<double>(calibration.n);
}

}  // namespace ssl_formation::evaluation
