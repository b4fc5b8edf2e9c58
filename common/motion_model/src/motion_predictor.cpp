#include "ssl_formation/motion_model/motion_predictor.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace ssl_formation {
inline namespace motion_model {

namespace {

// A 2-D isotropic Gaussian holds fraction p within sqrt(-ln(1 - p)) x its rms distance.
const double gaussian_z50 = std::sqrt(std::log(2.0));
const double gaussian_z90 = std::sqrt(std::log(10.0));

// The standard normal CDF, tabulated over [-8, 8] and interpolated linearly (error below 2e-6,
// far under what the calibration resolves): erfc for every cell edge of every robot and step
// was a third of the prediction time.
class NormalCdfTable {
 public:
  NormalCdfTable() {
    for (std::size_t i = 0; i < values_.size(); ++i) {
      const double z = -limit + static_cast<double>(i) / per_unit;
      values_[i] = 0.5 * std::erfc(-z / std::sqrt(2.0));
    }
  }
  double operator()(double z) const {
    if (!(z > -limit)) return 0.0;  // also NaN
    if (z >= limit) return 1.0;
    const double position = (z + limit) * per_unit;
    const auto i = static_cast<std::size_t>(position);
    const double fraction = position - static_cast<double>(i);
    return values_[i] + fraction * (values_[i + 1] - values_[i]);
  }

 private:
  static constexpr double limit = 8.0;
  static constexpr double per_unit = 128.0;  // 16 KiB: it stays in cache between frames
  std::array<double, static_cast<std::size_t>(2 * limit * per_unit) + 2> values_{};
};
const NormalCdfTable normal_cdf;

constexpr MotionKey empty_slot = ~MotionKey{0};  // no key has every bit set

// The first standing context whose robots have all stood at least `window_s`; one past the last
// if none has.
std::uint32_t standing_context_after(double window_s) {
  std::uint32_t context = 2;  // standing_context: 1 is "not yet standing_limits_s[0]"
  for (const double limit : MotionFeatures::standing_limits_s) {
    if (limit >= window_s) return context;
    ++context;
  }
  return MotionFeatures::standing_contexts;
}

std::uint64_t next_model_id() {
  static std::atomic<std::uint64_t> last{0};
  return ++last;
}

}  // namespace

MotionModel::MotionModel(const MotionTable& table, const Grid& grid, const FieldSize& field,
                         MotionModelSettings settings, const MotionModel* prior_model)
    : config_(table.config()), settings_(settings), id_(next_model_id()) {
  if (prior_model) {
    // The prior may have learned further ahead: its first horizons are the table's.
    MotionConfig same_horizons = prior_model->config_;
    same_horizons.horizons = config_.horizons;
    if (!(same_horizons == config_) || prior_model->config_.horizons < config_.horizons) {
      throw std::invalid_argument(
          "the prior table was trained with other motion model settings (step, windows, or "
          "fewer horizons) than the opponent's table");
    }
  }
  const int horizons = config_.horizons;
  settled_context_ = standing_context_after(config_.settle_window_s);
  long_settled_context_ = standing_context_after(config_.long_settle_window_s);

  std::vector<Estimate> generic_roots;
  MotionLevelEstimates::GenericEstimate generic;
  if (prior_model) {
    for (int h = 0; h < horizons; ++h) {
      generic_roots.push_back(prior_model->horizon_[static_cast<std::size_t>(h)].root);
    }
    generic = [prior_model](MotionKey key) { return prior_model->estimate(key); };
  }
  const MotionLevelEstimates estimates(table, settings_, prior_model ? &generic_roots : nullptr,
                                       generic);
  horizon_.resize(static_cast<std::size_t>(horizons));
  for (int h = 0; h < horizons; ++h) {
    Horizon& horizon = horizon_[static_cast<std::size_t>(h)];
    static_cast<MotionHorizonPrior&>(horizon) = estimates.horizon(h);
    horizon.z50.fill(gaussian_z50);
    horizon.z90.fill(gaussian_z90);
  }
  index_estimates(estimates, prior_model);
  for (int h = 0; h < horizons; ++h) {
    Horizon& horizon = horizon_[static_cast<std::size_t>(h)];
    if (!weigh_means(table, h) && prior_model) {
      horizon.mean_weight = prior_model->horizon_[static_cast<std::size_t>(h)].mean_weight;
    }
    calibrate(table, h, grid, field);
    if (prior_model && horizon.cell_calibration[0].empty() && horizon.cell_calibration[1].empty()) {
      // Too little held out of the opponent's own play to calibrate on: the prior's calibration.
      const Horizon& generic = prior_model->horizon_[static_cast<std::size_t>(h)];
      horizon.z50 = generic.z50;
      horizon.z90 = generic.z90;
      horizon.cell_calibration = generic.cell_calibration;
    }
  }
}

std::optional<MotionModel::Estimate> MotionModel::estimate(MotionKey key) const {
  const Slot* slot = find(key);
  if (!slot) return std::nullopt;
  Estimate e;
  e.mean_x = slot->mean_x;
  e.mean_y = slot->mean_y;
  e.mean_square = slot->mean_square;
  for (int i = 0; i < motion_regressors; ++i) {
    e.coefficients[static_cast<std::size_t>(i)] = slot->coefficients[static_cast<std::size_t>(i)];
  }
  return e;
}

void MotionModel::index_estimates(const MotionLevelEstimates& estimates,
                                  const MotionModel* prior_model) {
  // The rows only the prior has: a new opponent is predicted from every team's.
  std::vector<const Slot*> prior_only;
  // The pooled ablation reads no row (MotionModel::forecast starts it past the finest level):
  // an index of them would only take memory, as much as the model's.
  const bool rows_read = !settings_.pooled;
  if (prior_model && rows_read) {
    for (const Slot& slot : prior_model->index_) {
      if (slot.key != empty_slot && estimates.number(slot.key) == MotionRowMap::no_row) {
        prior_only.push_back(&slot);
      }
    }
  }
  std::size_t size = 16;
  const std::size_t keys = rows_read ? estimates.size() : 0;
  while (size < 2 * (keys + prior_only.size())) size *= 2;
  index_mask_ = size - 1;
  index_.assign(size, Slot{empty_slot, 0, 0, 0, {}});
  const auto place = [this](MotionKey key) -> Slot& {
    std::size_t slot = motion_key_slot(key, index_mask_);
    while (index_[slot].key != empty_slot) slot = (slot + 1) & index_mask_;
    return index_[slot];
  };
  for (std::size_t i = 0; i < keys; ++i) {
    const Estimate& e = estimates.estimate(i);
    Slot& slot = place(estimates.key(i));
    slot = Slot{estimates.key(i),
                static_cast<float>(e.mean_x),
                static_cast<float>(e.mean_y),
                static_cast<float>(e.mean_square),
                {}};
    for (int c = 0; c < motion_regressors; ++c) {
      slot.coefficients[static_cast<std::size_t>(c)] =
          static_cast<float>(e.coefficients[static_cast<std::size_t>(c)]);
    }
  }
  for (const Slot* generic : prior_only) place(generic->key) = *generic;
}

const MotionModel::Slot* MotionModel::find(MotionKey key) const {
  for (std::size_t slot = motion_key_slot(key, index_mask_);; slot = (slot + 1) & index_mask_) {
    if (index_[slot].key == key) return &index_[slot];
    if (index_[slot].key == empty_slot) return nullptr;
  }
}

MotionModel::RobotKeys MotionModel::motion_keys(const MotionRobot& robot) {
  const Point v = robot.has_velocity ? robot.kinematics.velocity : Point{};
  MotionInstance instance;
  instance.robot_id = robot.robot_id;
  instance.x = whole_mm(robot.position.x);
  instance.y = whole_mm(robot.position.y);
  instance.v_x = whole_mm(v.x);
  instance.v_y = whole_mm(v.y);
  instance.context = robot.context;
  RobotKeys keys{};
  keys[0] = encode_motion_key(motion_key_parts(0, instance));
  for (std::size_t level = 1; level < keys.size(); ++level) {
    keys[level] = coarser_motion_key(keys[level - 1]);
  }
  return keys;
}

MotionForecast MotionModel::forecast(int horizon_index, const MotionRobot& robot) const {
  return forecast(horizon_index, robot, motion_keys(robot));
}

MotionForecast MotionModel::forecast(int horizon_index, const MotionRobot& robot,
                                     const RobotKeys& keys) const {
  return forecast(horizon_index, robot, resolve(horizon_index, keys));
}

MotionModel::Resolved MotionModel::resolve(int horizon_index, const RobotKeys& keys) const {
  const Horizon& horizon = horizon_[static_cast<std::size_t>(horizon_index)];
  const MotionKey horizon_bits = encode_motion_key({horizon_index, MotionLevel::robot, 0, 0, 0, 0});
  // In HALT every robot stands, wherever it is: its forecasts read the velocity level's rows
  // (motion_finest_level_read).
  const std::uint32_t context = decode_motion_key(keys[0]).context;
  const std::uint32_t game = MotionFeatures::game_context_of(context);
  const bool halted = game == MotionFeatures::halt_game;
  const auto phase = static_cast<std::size_t>(MotionFeatures::phase_of_game_context(game));
  const double mean_weight = horizon.mean_weight[phase];  // 0 in HALT: the same drift each time
  const std::int8_t place = place_regressor(context);
  // The pooled ablation looks up no row: every robot gets what a robot with no row at all gets,
  // below.
  const std::size_t first_level =
      settings_.pooled ? keys.size() : static_cast<std::size_t>(motion_finest_level_read(context));
  for (std::size_t level = first_level; level < keys.size(); ++level) {
    if (const Slot* found = find(keys[level] | horizon_bits)) {
      Resolved e;
      // The rows' mean displacement, as much of it as the phase keeps (Horizon::mean_weight).
      e.mean_x = mean_weight * found->mean_x;
      e.mean_y = mean_weight * found->mean_y;
      e.mean_square = found->mean_square;
      for (int i = 0; i < motion_regressors; ++i) e.coefficients[i] = found->coefficients[i];
      e.z50 = horizon.z50[phase];
      e.z90 = horizon.z90[phase];
      e.level = static_cast<MotionLevel>(level);
      e.place_regressor = place;
      e.halted = halted;
      return e;
    }
  }
  const Estimate& prior = horizon.prior_of(context);
  return Resolved{mean_weight * prior.mean_x,
                  mean_weight * prior.mean_y,
                  prior.mean_square,
                  prior.coefficients,
                  horizon.z50[phase],
                  horizon.z90[phase],
                  MotionLevel::all,
                  place,
                  halted};
}

std::int8_t MotionModel::place_regressor(std::uint32_t context) const {
  const std::uint32_t standing = context % MotionFeatures::standing_contexts;
  if (standing >= long_settled_context_) return 3;  // to_settled_mean
  if (standing >= settled_context_) return 2;       // to_recent_mean
  return -1;
}

bool MotionModel::stands(const MotionRobot& robot, const Resolved& e,
                         const MotionRegressors& x) const {
  const Point v = robot.kinematics.velocity;
  const double speed2 = v.x * v.x + v.y * v.y;
  if (speed2 < settings_.stay_speed_mm_s * settings_.stay_speed_mm_s) return true;
  const double standing = MotionFeatures::speed_limits_mm_s[0];
  if (speed2 >= standing * standing) return false;
  const Point to_recent = robot.kinematics.to_recent_mean;
  if (to_recent.x * to_recent.x + to_recent.y * to_recent.y <=
      settings_.stay_spread_mm * settings_.stay_spread_mm) {
    return true;
  }
  // In HALT and timeouts no robot may move (SSL rules, Referee Commands: Halt): one that has
  // stood a settle window, its mean sighting within the vision's noise, stands though it creeps.
  return e.halted && way_to_place(e, x);
}

const Point* MotionModel::way_to_place(const Resolved& e, const MotionRegressors& x) const {
  if (e.place_regressor < 0) return nullptr;
  const Point& way = x[static_cast<std::size_t>(e.place_regressor)];
  const double noise = settings_.halt_error_mm;
  return way.x * way.x + way.y * way.y <= noise * noise ? &way : nullptr;
}

void MotionModel::Cache::clear() {
  model_id_ = 0;
  estimates_.clear();
}

const MotionModel::Resolved* MotionModel::resolve_all(
    const MotionRobot& robot, std::size_t horizons, Cache* cache,
    std::array<Resolved, MotionConfig::max_horizons>& scratch) const {
  const RobotKeys keys = motion_keys(robot);
  Resolved* out = scratch.data();
  if (cache) {
    if (cache->model_id_ != id_ || cache->horizons_ != horizons) {
      cache->model_id_ = id_;
      cache->horizons_ = horizons;
      cache->keys_.fill(empty_slot);
      cache->estimates_.assign(cache->keys_.size() * horizons, Resolved{});
    }
    const auto slot = static_cast<std::size_t>(MotionFeatures::robot_slot(robot.robot_id));
    out = cache->estimates_.data() + slot * horizons;
    // The key holds the robot slot, so an entry is only ever this slot's.
    if (cache->keys_[slot] == keys[0]) return out;
    cache->keys_[slot] = keys[0];
  }
  for (std::size_t h = 0; h < horizons; ++h) out[h] = resolve(static_cast<int>(h), keys);
  return out;
}

MotionForecast MotionModel::forecast(int horizon_index, const MotionRobot& robot,
                                     const Resolved& e) const {
  const Horizon& horizon = horizon_[static_cast<std::size_t>(horizon_index)];
  MotionForecast f;
  f.level = e.level;
  f.from_counts = horizon.root.n > 0.0;
  const double horizon_s = (horizon_index + 1) * config_.step_s;
  f.position = robot.position;
  // A robot without a velocity counts as standing, and a standing robot stays (stands()): most
  // of them are still standing at the horizon, and the few that set off go where the rows cannot
  // tell. The rows' fit is the mean of both, where the mean of squared errors is least; the
  // distance a team judges a forecast by is least at the median, which is where the robot
  // stands. Running play at 1 s on seeds 11/12: robots under 250 mm/s that stayed within 100 mm
  // were 38.0 mm off with the rows' fit, 10.7 with persistence. On the tuning seeds (11/12,
  // 13/14, 15/16, 17/18 with 3 mm of noise) running play at 1 s came 2.3-4.3% nearer and STOP
  // 3.2-7.7% (docs/results.md).
  if (!robot.has_velocity) {
    f.stays = true;
  } else {
    const MotionRegressors x = motion_regressors_of(robot.kinematics, horizon_s);
    if (stands(robot, e, x)) {
      // At the mean of its sightings over the time it has stood, if they are within the vision's
      // noise of it: nearer its place than the last sighting, which carries that noise (HALT of
      // the simulated match of seeds 11/12 with 3 mm of noise, 0.2 s: 5.0 mm off so, 7.2 at
      // the last sighting, 8.5 with the rows' fit). The rows cannot learn it: their coefficients
      // are held towards the parent's by instances of a 500 mm regressor, and a standing
      // robot's are a few millimetres.
      if (const Point* way = way_to_place(e, x)) {
        f.position = {robot.position.x + way->x, robot.position.y + way->y};
      }
      f.stays = true;
    } else {
      f.position = {robot.position.x + e.mean_x, robot.position.y + e.mean_y};
      for (int i = 0; i < motion_regressors; ++i) {
        f.position.x += e.coefficients[i] * x[i].x;
        f.position.y += e.coefficients[i] * x[i].y;
      }
    }
  }
  f.mean_square_mm2 = e.mean_square;
  const double rms = std::sqrt(f.mean_square_mm2);
  f.radius50_mm = e.z50 * rms;
  f.radius90_mm = e.z90 * rms;
  return f;
}

double MotionModel::gaussian_cell_mass(const MotionForecast& forecast, const Grid& grid,
                                       const FieldSize& field, Cell cell) {
  // Per axis the variance is half the expected squared distance.
  const double inverse_s = 1.0 / std::sqrt(std::max(forecast.mean_square_mm2, 1.0) / 2.0);
  const auto axis = [inverse_s](double mean, int index, int cells, double extent) {
    const double size = extent / cells;
    const double low = -extent / 2.0 + index * size;
    // Edge cells hold everything beyond the field (Grid::cell_of clamps).
    const double below = index == 0 ? 0.0 : normal_cdf((low - mean) * inverse_s);
    const double up_to = index == cells - 1 ? 1.0 : normal_cdf((low + size - mean) * inverse_s);
    return up_to - below;
  };
  return axis(forecast.position.x, cell.x, grid.length(), field.length_mm) *
         axis(forecast.position.y, cell.y, grid.width(), field.width_mm);
}

double MotionModel::IsotonicMap::operator()(double mass) const {
  if (mass_upper.empty()) return mass;
  const auto it = std::lower_bound(mass_upper.begin(), mass_upper.end(), mass);
  if (it == mass_upper.end()) return hit_rate.back();
  return hit_rate[static_cast<std::size_t>(it - mass_upper.begin())];
}

double MotionModel::calibrated(int horizon_index, double mass, bool stays) const {
  const Horizon& horizon = horizon_[static_cast<std::size_t>(horizon_index)];
  const IsotonicMap& map = horizon.cell_calibration[stays ? 1 : 0];
  // A table whose held-out sample had no robot of this kind: the other kind's map.
  return map.empty() ? horizon.cell_calibration[stays ? 0 : 1](mass) : map(mass);
}

double MotionModel::cell_probability(int horizon_index, const MotionForecast& forecast,
                                     const Grid& grid, const FieldSize& field, Cell cell) const {
  return calibrated(horizon_index, gaussian_cell_mass(forecast, grid, field, cell), forecast.stays);
}

Point MotionRules::apply(std::uint32_t robot_id, Point from, double horizon_s, Point to) const {
  if (exempt_robot_id && *exempt_robot_id == robot_id) return to;
  // A robot still on its way back is not held: only one in its half already stays there.
  const bool hold_in_half = own_half && from.x <= 0.0;
  if (hold_in_half) to.x = std::min(to.x, 0.0);
  const double reach = max_speed_mm_s * horizon_s;
  const auto within_reach = [&](Point p) {
    return std::hypot(p.x - from.x, p.y - from.y) <= reach * (1.0 + 1e-9);
  };
  if (!within_reach(to)) {  // the nearest point within reach is on the line towards `to`
    const double scale = reach / std::hypot(to.x - from.x, to.y - from.y);
    to = {from.x + (to.x - from.x) * scale, from.y + (to.y - from.y) * scale};
  }
  if (!keep_away_from) return to;
  // The area to keep away from: the ball's circle, or with keep_away_to the stadium about the
  // segment from the ball to it. `nearest` is the segment's point nearest to `p`.
  const Point ball = *keep_away_from;
  const Point end = keep_away_to.value_or(ball);
  const auto nearest = [&](Point p) {
    const Point along{end.x - ball.x, end.y - ball.y};
    const double length_squared = along.x * along.x + along.y * along.y;
    if (length_squared < 1e-9) return ball;
    const double t = std::clamp(
        ((p.x - ball.x) * along.x + (p.y - ball.y) * along.y) / length_squared, 0.0, 1.0);
    return Point{ball.x + t * along.x, ball.y + t * along.y};
  };
  const auto clear_of_ball = [&](Point p) {
    const Point n = nearest(p);
    return std::hypot(p.x - n.x, p.y - n.y) >= keep_away_mm * (1.0 - 1e-9);
  };
  if (clear_of_ball(to)) return to;
  // Pushed out to the edge, away from the segment (or along where the robot stands from it).
  Point centre = nearest(to);
  Point away{to.x - centre.x, to.y - centre.y};
  double length = std::hypot(away.x, away.y);
  if (length < 1e-6) {
    centre = nearest(from);
    away = {from.x - centre.x, from.y - centre.y};
    length = std::hypot(away.x, away.y);
  }
  if (length < 1e-6) {
    // On the segment: off it sideways, or towards its own goal for a bare ball.
    const Point along{end.x - ball.x, end.y - ball.y};
    const double along_length = std::hypot(along.x, along.y);
    away = along_length > 1e-6 ? Point{-along.y, along.x} : Point{-1.0, 0.0};
    length = along_length > 1e-6 ? along_length : 1.0;
  }
  Point pushed{centre.x + away.x / length * keep_away_mm,
               centre.y + away.y / length * keep_away_mm};
  if (hold_in_half) pushed.x = std::min(pushed.x, 0.0);
  if (within_reach(pushed)) return pushed;
  // Out of reach both ways: a robot clear of the area now can stay where it is; one that is not
  // must leave, whatever its speed.
  return clear_of_ball(from) ? from : pushed;
}

void MotionModel::predict(const std::vector<MotionRobot>& robots, int horizon,
                          const StateCodec& codec, const FieldSize& field, AttackDirection attacks,
                          Prediction& out, const MotionRules& rules) const {
  predict(robots, horizon, codec, field, attacks, out, nullptr, rules, nullptr);
}

void MotionModel::predict(const std::vector<MotionRobot>& robots, int horizon,
                          const StateCodec& codec, const FieldSize& field, AttackDirection attacks,
                          Prediction& out, Cache& cache, const MotionRules& rules,
                          const SetPlayAdvice* advice) const {
  predict(robots, horizon, codec, field, attacks, out, &cache, rules, advice);
}

void MotionModel::predict(const std::vector<MotionRobot>& robots, int horizon,
                          const StateCodec& codec, const FieldSize& field, AttackDirection attacks,
                          Prediction& out, Cache* cache, const MotionRules& rules,
                          const SetPlayAdvice* advice) const {
  const bool ruled = rules.any();
  const bool advised = advice && advice->any && advice->robots.size() == robots.size();
  const Grid& grid = codec.grid();
  const auto steps = static_cast<std::size_t>(horizon);
  out.steps.resize(steps);
  for (PredictedStep& step : out.steps) step.robots.resize(robots.size());
  const int learned = config_.horizons;

  // The learned horizons this prediction reaches.
  const auto resolved = static_cast<std::size_t>(std::min(horizon, learned));
  for (std::size_t r = 0; r < robots.size(); ++r) {
    const MotionRobot& robot = robots[r];
    // The two forecasts before the current step, as the rows made them (before any advice and
    // the rules, which then apply to the extrapolated steps once), for extrapolating beyond the
    // learned ones.
    MotionForecast before_last{robot.position, 0.0, 0.0, 0.0, MotionLevel::all, true};
    MotionForecast last = before_last;
    Cell previous = grid.cell_of(robot.position, field);
    std::array<Resolved, MotionConfig::max_horizons> scratch;
    const Resolved* estimates = resolve_all(robot, resolved, cache, scratch);
    for (int k = 1; k <= horizon; ++k) {
      MotionForecast f;
      int calibration_index = k - 1;
      if (k <= learned) {
        f = forecast(k - 1, robot, estimates[k - 1]);
      } else {
        calibration_index = learned - 1;
        f = last;
        f.position = {2.0 * last.position.x - before_last.position.x,
                      2.0 * last.position.y - before_last.position.y};
        f.radius50_mm = 2.0 * last.radius50_mm - before_last.radius50_mm;
        f.radius90_mm = 2.0 * last.radius90_mm - before_last.radius90_mm;
        const double rms =
            std::sqrt(last.mean_square_mm2) * 2.0 - std::sqrt(before_last.mean_square_mm2);
        f.mean_square_mm2 = rms * rms;
      }
      before_last = last;
      last = f;
      if (advised && k <= static_cast<int>(SetPlayAdvice::Robot{}.weight.size())) {
        const SetPlayAdvice::Robot& recalled = advice->robots[r];
        const auto step = static_cast<std::size_t>(k - 1);
        const double w = recalled.weight[step];
        f.position = {f.position.x + w * (recalled.position[step].x - f.position.x),
                      f.position.y + w * (recalled.position[step].y - f.position.y)};
      }
      if (ruled) {
        f.position = rules.apply(robot.robot_id, robot.position, k * config_.step_s, f.position);
      }
      const Cell cell = grid.cell_of(f.position, field);
      RobotPrediction& p = out.steps[static_cast<std::size_t>(k - 1)].robots[r];
      p.robot_id = robot.robot_id;
      p.position = cell;
      p.previous = previous;
      p.probability = cell_probability(calibration_index, f, grid, field, cell);
      p.unseen = !f.from_counts;
      p.feed_position = normalise(f.position, attacks);
      p.radius50_mm = f.radius50_mm;
      p.radius90_mm = f.radius90_mm;
      p.mean_square_mm2 = f.mean_square_mm2;
      p.normalised_position = f.position;
      p.stays = f.stays;
      previous = cell;
    }
  }

  double confidence = 1.0;
  for (PredictedStep& step : out.steps) {
    Point centroid{};
    double mean_square = 0.0;
    double formation = 1.0;
    bool unseen = false;
    for (const RobotPrediction& p : step.robots) {
      centroid.x += p.normalised_position.x;
      centroid.y += p.normalised_position.y;
      mean_square += p.mean_square_mm2;
      formation *= formation_factor(p, p.probability);
      unseen = unseen || p.unseen;
    }
    const double n = static_cast<double>(std::max<std::size_t>(step.robots.size(), 1));
    centroid = {centroid.x / n, centroid.y / n};
    step.centroid = grid.cell_of(centroid, field);
    // The mean of n independent errors: the Gaussian mass of its cell, not calibrated.
    MotionForecast mean_forecast;
    mean_forecast.position = centroid;
    mean_forecast.mean_square_mm2 = mean_square / (n * n);
    step.centroid_probability = gaussian_cell_mass(mean_forecast, grid, field, step.centroid);
    step.centroid_unseen = unseen;
    const auto centroid_id = static_cast<StateIndex>(grid.cell_id(step.centroid));
    for (RobotPrediction& p : step.robots) {
      p.state = codec.compose(centroid_id, static_cast<StateIndex>(grid.cell_id(p.position)),
                              static_cast<StateIndex>(grid.cell_id(p.previous)));
    }
    step.formation_probability = formation;
    confidence *= formation;
    step.confidence = confidence;
  }
}

}  // namespace motion_model
}  // namespace ssl_formation
