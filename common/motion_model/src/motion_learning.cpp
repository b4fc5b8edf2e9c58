#include "ssl_formation/motion_model/motion_learning.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "ssl_formation/motion_model/braking_advice.hpp"
#include "ssl_formation/motion_model/game_rules.hpp"
#include "ssl_formation/motion_model/motion_table_pruning.hpp"

namespace ssl_formation {
inline namespace motion_model {

namespace {

// The history the motion model's predictions read velocities from: the step and horizons come
// from the table, but velocities need only the window, which is the same for every table.
MotionConfig prediction_history_config(const MotionForecastSettings& settings) {
  MotionConfig motion;
  motion.step_s = settings.step_s;
  motion.horizons = 1;
  return motion;
}

// The game context a motion history files the moment's robots under.
std::uint32_t game_context_of(const MatchMoment& moment) {
  return MotionFeatures::game_context(moment.phase, moment.since_command_s);
}

// The ball's velocity as a motion history takes it: zero when no ball is seen.
Point ball_velocity_of(const MatchMoment& moment) {
  return moment.ball ? moment.ball_velocity : Point{};
}

}  // namespace

MotionLearner::MotionLearner(TransitionTable table, MotionTable motion,
                             std::optional<OnlineCalibrationSettings> recalibration, bool pooled,
                             std::size_t rows_in_memory)
    : table_(std::move(table)),
      motion_(std::move(motion)),
      rows_in_memory_(rows_in_memory),
      history_(motion_.config()),
      set_plays_(motion_.config().horizons * motion_.config().step_s),
      recalibration_(recalibration),
      pooled_(pooled) {}

void MotionLearner::observe(const MatchMoment& moment) {
  // Followed in every state, so that velocities are known when learning starts again.
  history_.add(moment.formation(), game_context_of(moment), ball_velocity_of(moment));
}

void MotionLearner::learn(const MatchMoment& moment) {
  for (const Transition& t : moment.sample.transitions) table_.add(t.from, t.to);
  learn_motion(motion_, history_, moment.formation(), moment.learn_from_s);
  set_plays_.record(moment.formation().time_s, moment.phase,
                    moment.game_state == GameState::kickoff_preparation, moment.since_command_s,
                    moment.formation(), motion_.set_plays());
  bound_memory();
}

void MotionLearner::bound_memory() {
  if (rows_in_memory_ == 0 || motion_.rows() <= rows_in_memory_) return;
  // Pruned as a table is saved, by the same rule (the budget's defaults), and then to half the
  // bound, the rows that gain least folded first: every coarser key's sums stay exact, a folded
  // robot row that goes on gaining starts again beneath its zone, and the next pruning waits
  // for half the bound's rows, so that its cost (one estimate per key) stays a fixed share of
  // the learning.
  MotionPruning pruning;
  pruning.max_rows = std::max<std::size_t>(1, rows_in_memory_ / 2);
  motion_ = prune_motion_table(motion_, MotionModelSettings{}, pruning).table;
}

void MotionLearner::forget_match() {
  history_.clear();
  set_plays_.finish(motion_.set_plays());
}

void MotionLearner::absorb(const Learner& other) {
  const auto* motion = dynamic_cast<const MotionLearner*>(&other);
  if (!motion) throw std::invalid_argument("a training of another model cannot be added");
  if (!(motion_.config() == motion->motion_.config())) {
    throw std::invalid_argument("a training with other motion model settings cannot be added");
  }
  table_.merge(motion->table_);  // checks the grid
  motion_.merge(motion->motion_);
  bound_memory();
}

std::unique_ptr<Forecaster> MotionLearner::forecaster(const TableMetadata& metadata) const {
  return forecaster(metadata, nullptr);
}

std::unique_ptr<Forecaster> MotionLearner::forecaster(
    const TableMetadata& metadata, std::shared_ptr<const MotionTable> prior_table) const {
  MotionForecastSettings settings;
  settings.prior_table = std::move(prior_table);
  settings.prior_field = metadata.field;
  settings.grid = table_.grid();
  settings.step_s = motion_.config().step_s;
  settings.recalibration = recalibration_;
  settings.pooled = pooled_;
  auto forecaster = std::make_unique<MotionForecaster>(settings);
  forecaster->set_table(std::make_shared<const StoredTable>(*stored(metadata)));
  return forecaster;
}

std::optional<StoredTable> MotionLearner::stored(const TableMetadata& metadata) const {
  return StoredTable{table_, metadata, std::make_shared<const MotionTable>(motion_)};
}

std::optional<TableSummary> MotionLearner::table_summary() const {
  return TableSummary{
      table_.grid(), table_.transitions(), table_.rows_seen(),
      table_.memory_bytes() + motion_.memory_bytes(),
      TableSummary::Motion{motion_.config().step_s, motion_.config().horizons, motion_.instances(),
                           motion_.held_out(), motion_.rows()}};
}

std::optional<StoredTable> MotionLearner::release_table(const TableMetadata& metadata) {
  StoredTable stored{std::move(table_), metadata,
                     std::make_shared<const MotionTable>(std::move(motion_))};
  table_ = TransitionTable(stored.table.grid());
  motion_ = MotionTable(stored.motion->config());
  return stored;
}

MotionForecaster::MotionForecaster(const MotionForecastSettings& settings)
    : settings_(settings),
      history_(prediction_history_config(settings)),
      calibration_(settings.recalibration.value_or(OnlineCalibrationSettings{})) {
  if (settings_.recalibration && !settings_.recalibration->valid()) {
    throw std::invalid_argument(
        "the recalibration's half-life must be positive seconds, its prior weight, tolerance and "
        "remember interval finite and not negative");
  }
  // Allocated now rather than wherever the first sample leaves it: a daemon woken every 16 ms
  // pays for every cold page its hot path touches.
  robots_.reserve(16);
  if (settings_.prior_table) {
    if (std::abs(settings_.prior_table->config().step_s - settings_.step_s) > 1e-9) {
      throw std::invalid_argument("the prior table's motion model was trained with another step");
    }
    prior_model_ = std::make_shared<const MotionModel>(*settings_.prior_table, settings_.grid,
                                                       settings_.prior_field, model_settings());
    model_ = prior_model_;
  }
}

PreparedTable MotionForecaster::prepare_table(std::shared_ptr<const StoredTable> table) const {
  if (!table) return PreparedTable{};
  if (!table->motion) {
    throw std::invalid_argument(
        "the table holds only the paper's counts (a version-1 table): it serves --model paper; "
        "train a table with --model motion to use the motion model");
  }
  if (std::abs(table->motion->config().step_s - settings_.step_s) > 1e-9) {
    throw std::invalid_argument("the table's motion model was trained with another step");
  }
  auto built = std::make_shared<BuiltTable>();
  built->model = std::make_shared<const MotionModel>(
      *table->motion, settings_.grid, table->metadata.field, model_settings(), prior_model_.get());
  built->set_plays = table->motion->set_plays();
  return PreparedTable{std::move(table), std::move(built)};
}

PreparedTable MotionForecaster::install_table(PreparedTable prepared) noexcept {
  // No copy of the stored table is kept (BuiltTable), and what was built of the previous one goes
  // back (the prior stays with this forecaster), for the caller to let go off the prediction path.
  PreparedTable old{nullptr, std::move(built_)};
  built_ = std::static_pointer_cast<const BuiltTable>(std::move(prepared.built));
  model_ = built_ ? built_->model : prior_model_;
  cache_.clear();
  return old;
}

void MotionForecaster::observe(const MatchMoment& moment) {
  history_.add(moment.formation(), game_context_of(moment), ball_velocity_of(moment));
  if (settings_.recalibration) calibration_.observe(moment.formation());
}

void MotionForecaster::forecast(const MatchMoment& moment, int steps, Prediction& out,
                                ForecastUse use) {
  robots_.clear();
  const std::uint32_t unmoving_context = MotionFeatures::context(
      0, 0, game_context_of(moment), MotionFeatures::ball_in_flight(ball_velocity_of(moment)));
  for (const FormationRobot& robot : moment.formation().robots) {
    const MotionHistory::Entry* seen = history_.latest(robot.robot_id);
    // The history has just taken this formation: `seen` is the robot's latest observation,
    // this frame's or (a robot carried over from an earlier frame) the one before. A robot
    // without a velocity yet is filed under the game's context alone.
    const bool moving = seen && seen->has_velocity;
    robots_.push_back({robot.robot_id, robot.position,
                       moving ? seen->kinematics : MotionKinematics{}, moving,
                       moving ? seen->context : unmoving_context});
  }
  // A kick-off being prepared: its robots walk to their places (SetPlayMemory's stage, and a
  // radius group of the recalibration's).
  const bool preparing = moment.game_state == GameState::kickoff_preparation;
  // At a kick-off of the opponent's, what its earlier kick-offs say (set_play_memory.hpp).
  const SetPlayAdvice* advice = nullptr;
  if (moment.phase == GamePhase::kickoff_opponent && built_ && !built_->set_plays.empty()) {
    built_->set_plays.recall(moment.formation(),
                             preparing ? SetPlayStage::preparation : SetPlayStage::taken,
                             moment.since_command_s, settings_.step_s, steps, set_play_advice_);
    advice = &set_play_advice_;
  } else if (moment.phase == GamePhase::ball_placement_opponent && moment.ball &&
             moment.designated_position) {
    advise_ball_placement(robots_, *moment.ball, *moment.designated_position, settings_.step_s,
                          steps, set_play_advice_);
    advice = &set_play_advice_;
  }
  // While robots take their places for a restart: those braking to a stop (braking_advice.hpp).
  if (braking_advice_holds(moment.phase)) {
    if (!advice) {
      set_play_advice_.robots.assign(robots_.size(), SetPlayAdvice::Robot{});
      set_play_advice_.any = false;
    }
    advise_braking(robots_, prediction_history_config(settings_).velocity_window_s,
                   settings_.step_s, steps, set_play_advice_);
    advice = &set_play_advice_;
  }
  model_->predict(robots_, steps, moment.codec, moment.field, moment.attacks, out, cache_,
                  rules_of_the_game(moment), advice);
  if (!settings_.recalibration) return;
  if (use == ForecastUse::predict) {
    calibration_.remember(out, moment.formation().time_s, settings_.step_s, moment.attacks,
                          moment.phase, preparing);
  }
  calibration_.adjust(out, moment.phase, preparing);
}

void MotionForecaster::forget_match() {
  history_.clear();
  calibration_.clear();
}

}  // namespace motion_model
}  // namespace ssl_formation
