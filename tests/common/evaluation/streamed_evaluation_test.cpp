// The evaluation read from logs as they go gives the figures it gave when it held everything in
// memory: here the reference runs every method on a front end of its own over the whole match
// kept in memory, keeps every prediction and every error, and sorts them; the streamed
// evaluation shares one front end between the methods, scores as it reads and keeps a histogram
// of the errors. Their means, medians and 90th percentiles agree to the 0.1 mm the report prints,
// in every row by game state, at every horizon, for every method.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "match_logs.hpp"
#include "moving_robots.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/evaluation/position_evaluation.hpp"
#include "ssl_formation/files/log_events.hpp"

namespace ssl_formation::evaluation {
namespace {

// The game controller's commands in turn, one every 4 s: stoppages, restarts of both teams,
// running play and a halt, so that the rows by game state fill.
constexpr std::array<Referee::Command, 10> commands{
    Referee::STOP,         Referee::FORCE_START, Referee::STOP, Referee::DIRECT_FREE_YELLOW,
    Referee::NORMAL_START, Referee::HALT,        Referee::STOP, Referee::PREPARE_KICKOFF_BLUE,
    Referee::NORMAL_START, Referee::FORCE_START};

// `seconds` of a match of the moving robots (the opponent yellow, attacking +x) as an official
// log, with its referee.
void write_log(const std::filesystem::path& path, std::uint64_t seed, double seconds,
               double start_s) {
  testing::MatchScript script;
  script.start_s = start_s;
  script.seconds = seconds;
  script.frame = [seed](double t) {
    DetectionFrameSpec spec;
    for (int index = 0; index < 12; ++index) {
      const RobotDetection robot{static_cast<std::uint32_t>(index % 6),
                                 testing::moving_robot_position(seed, index, t)};
      (index < 6 ? spec.yellow : spec.blue).push_back(robot);
    }
    return std::optional<DetectionFrameSpec>(spec);
  };
  script.referee = [](double t) {
    const auto n = static_cast<std::size_t>(t / 4.0);
    testing::RefereeSpec spec;
    spec.command = commands[n % commands.size()];
    spec.command_counter = static_cast<std::uint32_t>(n + 1);
    spec.yellow = "Opponent";
    spec.blue = "Us";
    spec.blue_on_positive_half = true;
    return std::optional<testing::RefereeSpec>(spec);
  };
  ASSERT_EQ(testing::write_match_log(path, script), "");
}

// A log read from the file at every replay, nothing of it kept.
EventStream log_stream(const std::filesystem::path& path) {
  return [path](MatchEventSink& sink) {
    Result<LogReader> reader = LogReader::open(path);
    ASSERT_TRUE(reader.has_value()) << reader.error().message;
    replay_log(*reader, sink);
    ASSERT_EQ(reader->ending(), LogReader::Ending::none) << reader->error();
  };
}

RecordedMatch in_memory(const std::filesystem::path& path) {
  Result<RecordedLog> log = read_recorded_log(path);
  EXPECT_TRUE(log.has_value());
  return log ? std::move(log->match) : RecordedMatch{};
}

// ---- The reference: every method on its own front end, everything kept, errors sorted.

struct Predicted {
  double time_s = 0.0;
  GamePhase phase = GamePhase::running;
  std::vector<PredictedStep> steps;
};

struct MethodRun {
  std::vector<Predicted> instants;
  std::vector<Formation> formations;  // the model's, the truth
};

// The evaluation's methods: the model, the baselines, then the pooled model.
std::vector<ModelKind> methods_of(const PositionEvaluationConfig& config) {
  std::vector<ModelKind> kinds{config.model};
  kinds.insert(kinds.end(), config.baselines.begin(), config.baselines.end());
  if (config.pooled_ablation && config.model == ModelKind::motion) kinds.push_back(config.model);
  return kinds;
}

std::vector<MethodRun> run_in_memory(const PositionEvaluationConfig& config,
                                     const RecordedMatch& train, const RecordedMatch& test) {
  const std::vector<ModelKind> kinds = methods_of(config);
  const std::size_t baselines_end = 1 + config.baselines.size();
  std::vector<PredictionConfig> predictions;
  std::vector<std::unique_ptr<Training>> trainings;
  for (std::size_t m = 0; m < kinds.size(); ++m) {
    PredictionConfig prediction;
    prediction.sampler = config.sampler;
    if (kinds[m] != config.model && sampling_problem(kinds[m], prediction.sampler.sampling)) {
      prediction.sampler.sampling = Sampling::frame;
    }
    prediction.horizon = config.steps;
    prediction.model = kinds[m];
    prediction.recalibration = config.recalibration;
    prediction.opponent = config.rules->opponent;
    TrainingConfig training;
    training.sampler = prediction.sampler;
    training.rules = config.rules;
    ModelSettings settings;
    settings.grid = config.sampler.grid;
    settings.step_s = config.sampler.step_s;
    settings.horizons = config.steps;
    settings.recalibration = config.recalibration;
    settings.velocity_window_s = config.velocity_window_s;
    settings.tolerance_s = config.tolerance_s;
    settings.pooled_motion = m >= baselines_end;
    trainings.push_back(
        std::make_unique<Training>(training, kinds[m], make_learner(kinds[m], settings)));
    trainings.back()->start_new_stream();
    train.replay(*trainings.back());
    predictions.push_back(prediction);
  }
  std::vector<MethodRun> runs(kinds.size());
  for (std::size_t m = 0; m < kinds.size(); ++m) {
    TableMetadata metadata;
    metadata.field = trainings[m]->sampler().field();
    metadata.step_s = config.sampler.step_s;
    metadata.samples = trainings.front()->samples();
    PredictionPipeline pipeline(
        predictions[m], trainings[m]->learner().forecaster(metadata, nullptr),
        [&runs, m](const PredictedFormation& p) {
          runs[m].instants.push_back({p.formation().time_s, p.context.phase, p.prediction.steps});
          if (m == 0) runs[m].formations.push_back(p.formation());
        });
    pipeline.start_new_stream();
    test.replay(pipeline);
  }
  return runs;
}

// The entry of `items` nearest `time_s` within `tolerance_s` (a tie: the later), as the
// evaluation pairs instants.
template <typename Items, typename TimeOf>
const typename Items::value_type* nearest(const Items& items, double time_s, double tolerance_s,
                                          TimeOf time_of) {
  const auto after = std::lower_bound(items.begin(), items.end(), time_s,
                                      [&](const auto& x, double t) { return time_of(x) < t; });
  const typename Items::value_type* best = nullptr;
  double best_gap = tolerance_s;
  for (auto it : {after == items.begin() ? items.end() : after - 1, after}) {
    if (it == items.end()) continue;
    const double gap = std::abs(time_of(*it) - time_s);
    if (gap <= best_gap) {
      best_gap = gap;
      best = &*it;
    }
  }
  return best;
}

double exact_percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  const double rank = p / 100.0 * static_cast<double>(values.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(rank));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (rank - static_cast<double>(below)) * (values[above] - values[below]);
}

std::string printed(double mm) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", mm);
  return text;
}

using Key = std::tuple<std::size_t, std::size_t, std::size_t>;  // row, horizon, method

// Every error of every row, horizon and method, as the evaluation pairs the predictions.
std::map<Key, std::vector<double>> errors_in_memory(const PositionEvaluationConfig& config,
                                                    const std::vector<MethodRun>& runs) {
  std::map<Key, std::vector<double>> errors;
  const auto time_of = [](const auto& x) { return x.time_s; };
  const MethodRun& model = runs.front();
  for (std::size_t i = 0; i < model.instants.size(); ++i) {
    const Predicted& instant = model.instants[i];
    std::vector<const Predicted*> at{&instant};
    for (std::size_t m = 1; m < runs.size(); ++m) {
      at.push_back(nearest(runs[m].instants, instant.time_s, config.tolerance_s, time_of));
    }
    if (std::find(at.begin(), at.end(), nullptr) != at.end()) continue;
    for (int k = 0; k < config.steps; ++k) {
      const auto h = static_cast<std::size_t>(k);
      const Formation* truth =
          nearest(model.formations, instant.time_s + (k + 1) * config.sampler.step_s,
                  config.tolerance_s, time_of);
      if (!truth) continue;
      for (const FormationRobot& robot : model.formations[i].robots) {
        const FormationRobot* actual = truth->find(robot.robot_id);
        if (!actual) continue;
        std::vector<double> robot_errors;
        for (const Predicted* method : at) {
          if (h >= method->steps.size()) break;
          const auto& guesses = method->steps[h].robots;
          const auto guess = std::find_if(guesses.begin(), guesses.end(), [&](const auto& g) {
            return g.robot_id == robot.robot_id;
          });
          if (guess == guesses.end()) break;
          robot_errors.push_back(std::hypot(guess->feed_position.x - actual->feed_position.x,
                                            guess->feed_position.y - actual->feed_position.y));
        }
        if (robot_errors.size() != at.size()) continue;
        for (const std::size_t row : {std::size_t{0}, state_row_of(instant.phase)}) {
          for (std::size_t m = 0; m < at.size(); ++m) {
            errors[{row, h, m}].push_back(robot_errors[m]);
          }
        }
      }
    }
  }
  return errors;
}

TEST(StreamedEvaluation, PrintsTheFiguresOfTheEvaluationThatHeldEverythingInMemory) {
  const testing::ScratchDir dir("sslf-streamed-evaluation");
  const std::filesystem::path train_log = dir.path() / "train.log";
  const std::filesystem::path test_log = dir.path() / "test.log";
  write_log(train_log, 1, 60.0, 100.0);
  write_log(test_log, 2, 40.0, 1000.0);

  PositionEvaluationConfig config;
  config.sampler.grid = Grid(6, 4);
  config.sampler.step_s = 0.5;
  config.sampler.sampling = Sampling::frame;
  config.steps = 3;
  OpponentChoice opponent;
  opponent.color = TeamColor::yellow;
  opponent.attacks = AttackDirection::positive_x;
  config.rules = MatchRules{opponent, LearnDuring::all};
  // Every row kept: the reference predicts from the tables as they were learned, and what is
  // compared here is the streaming, not the pruning (motion_table_pruning_test.cpp).
  config.table_budget.max_bytes = 0;
  config.table_budget.pruning.min_gain_nats = -std::numeric_limits<double>::infinity();
  const std::vector<PositionEvaluation> streamed =
      evaluate_positions({config}, {log_stream(train_log)}, {log_stream(test_log)});
  ASSERT_EQ(streamed.size(), 1u);
  const PositionEvaluation& result = streamed.front();
  EXPECT_TRUE(result.test_has_referee);

  const std::vector<MethodRun> runs =
      run_in_memory(config, in_memory(train_log), in_memory(test_log));
  ASSERT_EQ(runs.size(), result.methods.size());
  EXPECT_EQ(result.test_formations, runs.front().instants.size());
  const std::map<Key, std::vector<double>> errors = errors_in_memory(config, runs);

  std::size_t compared = 0;
  std::size_t phase_rows = 0;
  for (std::size_t row = 0; row < state_rows; ++row) {
    for (std::size_t h = 0; h < static_cast<std::size_t>(config.steps); ++h) {
      for (std::size_t m = 0; m < result.methods.size(); ++m) {
        SCOPED_TRACE(std::string(state_row_name(row)) + ", step " + std::to_string(h + 1) + ", " +
                     result.labels[m]);
        const ErrorStats& stats = result.rows[row][h].methods[m].error;
        const auto it = errors.find({row, h, m});
        if (it == errors.end()) {
          EXPECT_EQ(stats.count(), 0u);
          continue;
        }
        const std::vector<double>& kept = it->second;
        ASSERT_EQ(stats.count(), kept.size());
        // Summed in the same order: the same mean to the last bit.
        EXPECT_EQ(stats.mean(), std::accumulate(kept.begin(), kept.end(), 0.0) /
                                    static_cast<double>(kept.size()));
        EXPECT_EQ(printed(stats.median()), printed(exact_percentile(kept, 50.0)));
        EXPECT_EQ(printed(stats.percentile(90)), printed(exact_percentile(kept, 90.0)));
        ++compared;
        if (row != 0 && m == 0 && h == 0) ++phase_rows;
      }
    }
  }
  // The model, five baselines and the pooled model, at three steps, in "all" and the phases
  // the referee called.
  EXPECT_EQ(result.methods.size(), 7u);
  EXPECT_GE(phase_rows, 4u);
  EXPECT_GE(compared, 7u * 3u * 5u);
}

TEST(StreamedEvaluation, PercentilesStayWithinABinOfTheSortedErrors) {
  // Errors of every size, many sharing bins: the histogram's figures are within the width of the
  // bin they fall in (1/128 mm up to 32 mm, at most 1/2048 of the value beyond), its count and
  // mean exact.
  std::mt19937_64 random(7);
  std::lognormal_distribution<double> size(4.0, 1.5);
  ErrorStats stats;
  std::vector<double> kept;
  for (int i = 0; i < 200000; ++i) {
    const double error = i % 10 == 0 ? 0.0 : size(random);
    stats.add(error);
    kept.push_back(error);
  }
  ASSERT_EQ(stats.count(), kept.size());
  EXPECT_EQ(stats.mean(),
            std::accumulate(kept.begin(), kept.end(), 0.0) / static_cast<double>(kept.size()));
  for (const double p : {0.0, 5.0, 10.0, 25.0, 50.0, 75.0, 90.0, 99.0, 100.0}) {
    SCOPED_TRACE(p);
    const double exact = exact_percentile(kept, p);
    const double bin = std::max(1.0 / 128.0, exact / 2048.0);
    EXPECT_NEAR(stats.percentile(p), exact, bin);
  }
  // An error alone in its bin is known exactly.
  ErrorStats few;
  for (const double error : {1234.5678, 3.25, 77.0001}) few.add(error);
  EXPECT_NEAR(few.percentile(100), 1234.5678, 1e-4);
  EXPECT_NEAR(few.median(), 77.0001, 1e-5);
  EXPECT_NEAR(few.percentile(0), 3.25, 1e-6);
}

}  // namespace
}  // namespace ssl_formation::evaluation
