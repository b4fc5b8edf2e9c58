#pragma once
// One interface for every model: a Learner learns from the match, a Forecaster predicts from it.
// The paper's model, the motion model and the baselines (persistence, constant velocity, constant
// acceleration and their damped forms) implement both; model_factory.hpp makes them by name, and
// no code outside the factory asks which model it holds.
//
// Both see the match one sample at a time, as the front end (pipeline/match_front_end.hpp) hands
// it on: observe() for every sample, in time order, so that each keeps what it needs of the
// match so far (a robot's recent positions, its tracker); learn() or forecast() after it.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>

#include "ssl_formation/base/formation.hpp"
#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/base/prediction.hpp"
#include "ssl_formation/base/state.hpp"
#include "ssl_formation/match/game_phase.hpp"
#include "ssl_formation/match/referee.hpp"
#include "ssl_formation/model_api/stored_table.hpp"

namespace ssl_formation {
inline namespace model_api {

// What a status line and a report say of a learner's table, without a copy of it.
struct TableSummary {
  Grid grid;
  std::uint64_t transitions = 0;  // the counts on cells: their sum
  std::uint64_t states_seen = 0;  // the states with a count from them
  std::size_t memory_bytes = 0;   // what the table takes in memory, every section
  // The motion model's section, when the model keeps one.
  struct Motion {
    double step_s = 0.0;
    int horizons = 0;
    std::uint64_t instances = 0;  // learned from
    std::uint64_t held_out = 0;   // held out for the calibration
    std::size_t rows = 0;
  };
  std::optional<Motion> motion;
};

// One sample of the match and what the front end knows of it.
struct MatchMoment {
  const FormationSample& sample;
  const StateCodec& codec;
  FieldSize field;
  // The side the sample's positions were normalised with (the opponent attacks it in the feed).
  AttackDirection attacks = AttackDirection::positive_x;
  GameState game_state = GameState::unknown;
  // The phase of the game for the team predicted, and how long its referee command has held.
  GamePhase phase = GamePhase::running;
  double since_command_s = std::numeric_limits<double>::infinity();
  // The data time a learner may learn from: the first sample under the current referee command
  // when learning keeps the game's states apart, else -infinity (all of the stream so far). No
  // instance spans it.
  double learn_from_s = -std::numeric_limits<double>::infinity();
  // The ball as the front end follows it, normalised like the robots (none: no ball seen lately),
  // and its velocity (mm/s, normalised; zero until two sightings give one).
  std::optional<Point> ball;
  Point ball_velocity;
  // Where a ball placement takes the ball (the referee's designated position), normalised; none
  // outside placements or when the game controller does not say.
  std::optional<Point> designated_position;

  const Formation& formation() const { return sample.formation; }
};

class Forecaster;

class Learner {
 public:
  virtual ~Learner() = default;

  // Every sample, learned from or not, in time order.
  virtual void observe(const MatchMoment& moment) = 0;
  // After observe(): learn from this sample (the training's rules say when).
  virtual void learn(const MatchMoment& moment) = 0;
  // Forgets the match so far (another stream, or the opponent changed colour): nothing learned
  // spans the two. What was learned stays.
  virtual void forget_match() = 0;
  // Adds what `other`, of the same model and settings, learned apart (another log, another
  // thread), as if this learner had learned it too. Throws std::invalid_argument otherwise.
  virtual void absorb(const Learner& other) = 0;
  // Grows with everything learned or absorbed: a daemon saves only when it changed.
  virtual std::uint64_t progress() const = 0;

  // What a table file keeps of it, with `metadata`: a copy the caller may save or predict from.
  // None for a model that keeps no table (the baselines).
  virtual std::optional<StoredTable> stored(const TableMetadata& /*metadata*/) const {
    return std::nullopt;
  }
  // stored(), leaving this learner without its table, so that a large one is not copied: for a
  // caller done with learning (the evaluation, once it has trained).
  virtual std::optional<StoredTable> release_table(const TableMetadata& metadata) {
    return stored(metadata);
  }
  // What a status line says of that table, without copying it (none: no table).
  virtual std::optional<TableSummary> table_summary() const { return std::nullopt; }

  // A forecaster of what was learned so far; `metadata` is the table's (its field and step).
  virtual std::unique_ptr<Forecaster> forecaster(const TableMetadata& metadata) const = 0;
  // The same under a prior table (every team's; ModelSettings::prior_table), for a model that
  // has one: the motion model. The others ignore it.
  virtual std::unique_ptr<Forecaster> forecaster(
      const TableMetadata& metadata, std::shared_ptr<const MotionTable> /*prior_table*/) const {
    return forecaster(metadata);
  }
};

// A table as a forecaster predicts from it: the table, and what the forecaster built of it (the
// motion model's index; none for a model that reads the table as it is). Made by
// Forecaster::prepare_table, put in use by Forecaster::install_table of the same forecaster.
struct PreparedTable {
  std::shared_ptr<const StoredTable> table;
  std::shared_ptr<const void> built;
};

// What forecast() is for: a prediction that counts, or a rehearsal (the daemon runs the last one
// again just before a frame is due, to bring its caches back; it must change nothing).
enum class ForecastUse { predict, rehearse };

class Forecaster {
 public:
  virtual ~Forecaster() = default;

  // The table predictions come from (none: forget it). Throws std::invalid_argument, saying why,
  // for a table this model cannot use; the forecaster keeps its previous one then. What the
  // forecaster follows of the match (histories, recalibration) is kept across tables.
  void set_table(std::shared_ptr<const StoredTable> table) {
    install_table(prepare_table(std::move(table)));
  }
  // set_table in two steps, so that a daemon can build a large table's model (seconds) while it
  // goes on predicting from the old one. prepare_table does all the work and throws as set_table
  // does; it changes nothing and reads only what is fixed when the forecaster is made, so it may
  // run on another thread while this one forecasts. install_table puts the result in use between
  // two forecasts with a few pointer moves, and hands back the table it replaces: the caller
  // chooses where its memory is freed, which for a large model takes milliseconds.
  virtual PreparedTable prepare_table(std::shared_ptr<const StoredTable> table) const {
    return PreparedTable{std::move(table), nullptr};
  }
  virtual PreparedTable install_table(PreparedTable prepared) noexcept = 0;
  // Whether it can forecast now: a model that needs a table has one.
  virtual bool ready() const = 0;
  // Every sample, in time order, forecast from or not.
  virtual void observe(const MatchMoment& moment) = 0;
  // After observe(): predicts `steps` steps of the step ahead into `out`, reusing its storage.
  virtual void forecast(const MatchMoment& moment, int steps, Prediction& out,
                        ForecastUse use = ForecastUse::predict) = 0;
  // Forgets what it followed of the match (another stream, or the opponent changed colour).
  virtual void forget_match() = 0;
};

}  // namespace model_api
}  // namespace ssl_formation
