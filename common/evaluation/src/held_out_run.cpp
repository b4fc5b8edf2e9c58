// The steps of one held-out evaluation (held_out_run.hpp): the methods set up and trained, then
// each prediction on the test streams kept until its truth comes and scored.
#include "held_out_run.hpp"

namespace ssl_formation::evaluation::detail {

Evaluation::Evaluation(const PositionEvaluationConfig& config) : config_(config) {
  PositionEvaluation& result = result_;
  result.methods.push_back(config.model);
  result.methods.insert(result.methods.end(), config.baselines.begin(), config.baselines.end());
  result.baselines_end = result.methods.size();
  const RecordedPredictions* recorded = config.recorded_predictions.get();
  result.labels.emplace_back(recorded ? "predictions" : "model");
  result.model_states_cells = !recorded || recorded->has_cells;
  result.model_states_states = !recorded || recorded->has_states;
  for (const ModelKind kind : config.baselines) result.labels.emplace_back(describe(kind).label);
  if (config.pooled_ablation && describe(config.model).has_pooled_ablation && !recorded) {
    result.methods.push_back(config.model);
    result.labels.emplace_back("pooled model");
  }
  ModelSettings settings;
  settings.grid = config.sampler.grid;
  settings.step_s = config.sampler.step_s;
  settings.horizons = config.steps;
  settings.recalibration = config.recalibration;
  settings.velocity_window_s = config.velocity_window_s;
  settings.tolerance_s = config.tolerance_s;

  // Each method learns through its own Training, with the sampling it needs (the baselines read
  // every frame's velocities even where the model samples every step).
  for (std::size_t m = 0; m < result.methods.size(); ++m) {
    const ModelKind kind = result.methods[m];
    const bool ablation = m >= result.baselines_end;
    PredictionConfig prediction;
    prediction.sampler = config.sampler;
    if (kind != config.model && sampling_problem(kind, prediction.sampler.sampling)) {
      prediction.sampler.sampling = Sampling::frame;
    }
    prediction.horizon = config.steps;
    prediction.model = kind;
    prediction.recalibration = config.recalibration;
    prediction.opponent =
        config.rules ? std::optional<OpponentChoice>(config.rules->opponent) : std::nullopt;
    prediction.tracked_vision = config.tracked_vision;
    TrainingConfig training;
    training.sampler = prediction.sampler;
    training.rules = config.rules;
    training.tracked_vision = config.tracked_vision;
    ModelSettings own_settings = settings;
    own_settings.pooled_motion = ablation;
    // The ablation forecasts from the model's table (the same counts, the same sampling): it
    // learns nothing of its own.
    std::unique_ptr<Training> trained;
    if (!ablation) {
      MatchFrontEnd& front_end = training_front_ends_.of(Training::front_end_config(training));
      trained =
          std::make_unique<Training>(training, kind, make_learner(kind, own_settings), front_end);
    }
    methods_.push_back(
        {kind, prediction, std::move(trained), nullptr, {}, std::nullopt, own_settings});
  }
}

void Evaluation::end_training() {
  PositionEvaluation& result = result_;
  const PositionEvaluationConfig& config = config_;
  Training& model = *methods_.front().training;
  TableMetadata metadata;
  metadata.field = model.sampler().field();
  metadata.step_s = config.sampler.step_s;
  metadata.samples = model.samples();
  result.train_formations = model.samples();
  result.feed_problem = model.feed_problem();
  // Each table-keeping method's table as the programs save it, pruned to the budget: what a
  // team's predictor would read. Its training is done: the table is taken, not copied.
  const auto as_saved = [&config](Training& trained,
                                  const TableMetadata& own) -> std::shared_ptr<const StoredTable> {
    StoredTable saved = trained.release_table(own);
    if (saved.motion) {
      auto fit = fit_table_to_budget(saved.table, own, *saved.motion, config.table_budget);
      if (!fit) throw std::invalid_argument(fit.error().message);
      saved.motion = std::make_shared<const MotionTable>(std::move(fit->pruned.table));
    }
    return std::make_shared<const StoredTable>(std::move(saved));
  };
  if (model.keeps_table()) {
    const TableSummary summary = model.table_summary();
    result.transitions = summary.transitions;
    result.table_memory_bytes = summary.memory_bytes;
    result.table = as_saved(model, metadata);
  }

  result.rows.assign(state_rows, std::vector<HorizonScore>(static_cast<std::size_t>(config.steps)));
  for (auto& row : result.rows) {
    for (int k = 0; k < config.steps; ++k) {
      row[static_cast<std::size_t>(k)].horizon_s = (k + 1) * config.sampler.step_s;
      row[static_cast<std::size_t>(k)].methods.resize(methods_.size());
    }
  }

  for (std::size_t m = 0; m < methods_.size(); ++m) {
    Method& method = methods_[m];
    TableMetadata own = metadata;
    if (method.training) own.field = method.training->sampler().field();
    MatchFrontEnd& front_end =
        test_front_ends_.of(PredictionPipeline::front_end_config(method.prediction));
    std::shared_ptr<const MotionTable> prior =
        m == 0 || m >= result.baselines_end ? config.prior_table : nullptr;
    std::unique_ptr<Forecaster> forecaster;
    if (describe(method.kind).keeps_table) {
      // A table model and its ablation predict from the very table the result keeps, as the
      // programs save it (the learner's own forecaster would first build one of the rows before
      // pruning).
      ModelSettings own_settings = method.settings;
      own_settings.prior_table = std::move(prior);
      own_settings.prior_field = own.field;
      forecaster = make_forecaster(method.kind, own_settings);
      forecaster->set_table(m == 0 || !method.training ? result.table
                                                       : as_saved(*method.training, own));
    } else {
      forecaster = method.training->learner().forecaster(own, std::move(prior));
    }
    method.pipeline = std::make_unique<PredictionPipeline>(
        method.prediction, std::move(forecaster),
        [this, m](const PredictedFormation& p) { on_prediction(m, p); }, front_end);
  }
  // The forecasters hold what they need: the tables learned are let go before the testing, and
  // the result keeps the model's counts and metadata but not its motion rows (the forecaster
  // built its index of them; a season's rows are tens of megabytes per section).
  if (result.table && result.table->motion) {
    result.table = std::make_shared<const StoredTable>(
        StoredTable{result.table->table, result.table->metadata, nullptr});
  }
  training_front_ends_.clear();
  for (Method& method : methods_) method.training.reset();  // (the ablation had none)
}

void Evaluation::start_test_stream(std::size_t stream) {
  stream_ = stream;
  newest_s_ = -std::numeric_limits<double>::infinity();
  newest_model_s_ = newest_s_;
  test_front_ends_.start_new_stream();
}

void Evaluation::on_test_event(const MatchEvent& event) {
  if (event.kind == MatchEventKind::referee) result_.test_has_referee = true;
  test_front_ends_.on_event(event);
  score_ready(false);
}

void Evaluation::end_test_stream() { score_ready(true); }

void Evaluation::on_prediction(std::size_t m, const PredictedFormation& p) {
  if (m == 0 && config_.on_model_prediction) config_.on_model_prediction(p);
  const double time_s = p.formation().time_s;
  Instant instant{time_s, p.context.phase, {}};
  const RecordedPredictions* recorded = config_.recorded_predictions.get();
  if (m == 0 && recorded) {
    // The file's predictions at this instant, if it made any, in place of the sampling model's.
    const auto at = nearest_index(recorded->instants, time_s, recorded_time_tolerance_s,
                                  [](const RecordedPrediction& r) { return r.time_s; });
    if (at) {
      ++result_.recorded_matched;
      instant.steps = recorded->instants[*at].prediction.steps;
    }
  } else {
    instant.steps = p.prediction.steps;
  }
  newest_s_ = std::max(newest_s_, time_s);
  if (m == 0) {
    ++result_.test_formations;
    if (!model_.empty() && time_s < model_time(model_.back()) && !model_went_back_at_) {
      model_went_back_at_ = model_.size();
    }
    newest_model_s_ = std::max(newest_model_s_, time_s);
    model_.push_back({std::move(instant), p.formation()});
    return;
  }
  Method& method = methods_[m];
  if (!method.waiting.empty() && time_s < method.waiting.back().time_s && !method.went_back_at) {
    method.went_back_at = method.waiting.size();
  }
  method.waiting.push_back(std::move(instant));
}

void Evaluation::score_ready(bool ended) {
  const bool went_back = model_went_back_at_ ||
                         std::any_of(methods_.begin(), methods_.end(),
                                     [](const Method& m) { return m.went_back_at.has_value(); });
  if (went_back) {
    // A clock that went back (a restarted feed) ends the pairing: what came before it is scored
    // as at a stream's end, and what came after starts anew.
    std::deque<ModelInstant> model_after;
    if (model_went_back_at_) {
      model_after.assign(std::make_move_iterator(model_.begin() + *model_went_back_at_),
                         std::make_move_iterator(model_.end()));
      model_.erase(model_.begin() + *model_went_back_at_, model_.end());
    }
    std::vector<std::deque<Instant>> after(methods_.size());
    for (std::size_t m = 0; m < methods_.size(); ++m) {
      Method& method = methods_[m];
      if (!method.went_back_at) continue;
      after[m].assign(std::make_move_iterator(method.waiting.begin() + *method.went_back_at),
                      std::make_move_iterator(method.waiting.end()));
      method.waiting.erase(method.waiting.begin() + *method.went_back_at, method.waiting.end());
    }
    model_went_back_at_.reset();
    for (Method& method : methods_) method.went_back_at.reset();
    score_ready(true);
    model_ = std::move(model_after);
    for (std::size_t m = 0; m < methods_.size(); ++m) methods_[m].waiting = std::move(after[m]);
    newest_s_ = -std::numeric_limits<double>::infinity();
    for (const ModelInstant& x : model_) newest_s_ = std::max(newest_s_, model_time(x));
    newest_model_s_ = newest_s_;
    for (const Method& method : methods_) {
      for (const Instant& x : method.waiting) newest_s_ = std::max(newest_s_, x.time_s);
    }
  }
  while (!model_.empty() && (ended || ready(model_time(model_.front())))) {
    score_front();
    model_.pop_front();
  }
  if (ended) {
    for (Method& method : methods_) method.waiting.clear();
    return;
  }
  drop_stale();
}

bool Evaluation::ready(double time_s) const {
  if (newest_s_ >= time_s + config_.steps * config_.sampler.step_s + wait_limit_s) return true;
  // The truth of the last horizon: the model's first formation at or after it.
  if (newest_model_s_ < time_s + config_.steps * config_.sampler.step_s) return false;
  // Every method's nearest instant: its first at or after this one.
  return std::all_of(methods_.begin() + 1, methods_.end(), [&](const Method& method) {
    return (!method.waiting.empty() && method.waiting.back().time_s >= time_s) ||
           newest_s_ >= time_s + wait_limit_s;
  });
}

void Evaluation::drop_stale() {
  // No later model instant is earlier than this: a method's instants before its last one
  // earlier than this are never anyone's nearest.
  const double next_s = model_.empty() ? std::max(newest_model_s_, newest_s_ - wait_limit_s)
                                       : model_time(model_.front());
  for (std::size_t m = 1; m < methods_.size(); ++m) {
    std::deque<Instant>& waiting = methods_[m].waiting;
    while (waiting.size() >= 2 && waiting[1].time_s < next_s) waiting.pop_front();
  }
}

void Evaluation::score_front() {
  const PositionEvaluationConfig& config = config_;
  const Instant& instant = model_.front().instant;
  const Formation& now = model_.front().formation;
  // Each baseline's instant nearest the model's.
  std::vector<const Instant*> at(methods_.size(), nullptr);
  at[0] = &instant;
  for (std::size_t m = 1; m < methods_.size(); ++m) {
    const std::deque<Instant>& waiting = methods_[m].waiting;
    const auto j = nearest_index(waiting, instant.time_s, config.tolerance_s, instant_time);
    if (!j) return;  // scored on the same instants or not at all
    at[m] = &waiting[*j];
  }
  const std::array<std::size_t, 2> rows{0, state_row_of(instant.phase)};
  // What a file of predictions does not state is not scored for it (method 0): its cells, its
  // states, and the probabilities that need them.
  const RecordedPredictions* file = config.recorded_predictions.get();
  const bool scores_cells = !file || file->has_cells;
  const bool scores_states = !file || file->has_states;
  const bool scores_robot_probability = !file || (file->has_cells && file->has_probabilities);
  const bool scores_formation_probability =
      !file || (file->has_cells && file->has_formation_probability);
  const double step_s = config.sampler.step_s;
  for (int k = 0; k < config.steps; ++k) {
    const auto h = static_cast<std::size_t>(k);
    const auto truth_at =
        nearest_index(model_, instant.time_s + (k + 1) * step_s, config.tolerance_s, model_time);
    if (!truth_at) continue;
    const Formation* truth = &model_[*truth_at].formation;
    // The robots every method predicted and the truth holds.
    struct Scored {
      const FormationRobot* now;
      const FormationRobot* actual;
      std::vector<const RobotPrediction*> guesses;
    };
    std::vector<Scored> scored;
    for (const FormationRobot& robot : now.robots) {
      const FormationRobot* actual = truth->find(robot.robot_id);
      if (!actual) continue;
      Scored s{&robot, actual, std::vector<const RobotPrediction*>(at.size(), nullptr)};
      bool everyone = true;
      for (std::size_t m = 0; m < at.size() && everyone; ++m) {
        if (h >= at[m]->steps.size()) {
          everyone = false;
          break;
        }
        s.guesses[m] = find_robot(at[m]->steps[h], robot.robot_id);
        everyone = s.guesses[m] != nullptr;
      }
      if (everyone) scored.push_back(std::move(s));
    }
    if (scored.empty()) continue;
    if (config.on_sample) {
      for (const Scored& s : scored) {
        config.on_sample(ScoredSample{step_s, k + 1, stream_, instant.time_s, s.now->robot_id,
                                      instant.phase, s.now->feed_position, s.actual->feed_position,
                                      &s.guesses});
      }
    }
    for (const std::size_t row : rows) {
      HorizonScore& score = result_.rows[row][h];
      bool every_cell_right = true;
      for (std::size_t m = 0; m < at.size(); ++m) {
        MethodScore& method = score.methods[m];
        ++method.cells.formations;
        for (const Scored& s : scored) {
          const RobotPrediction& guess = *s.guesses[m];
          const double error = distance(guess.feed_position, s.actual->feed_position);
          method.error.add(error);
          ++method.cells.robots;
          if ((m != 0 || scores_states) && guess.state == s.actual->state) {
            ++method.cells.exact_states;
          }
          const bool right = guess.position == s.actual->cell;
          if ((m != 0 || scores_cells) && right) ++method.cells.exact_cells;
          if (m != 0 || scores_cells) {
            method.cells.cell_distance +=
                static_cast<std::uint64_t>(std::abs(guess.position.x - s.actual->cell.x) +
                                           std::abs(guess.position.y - s.actual->cell.y));
          }
          if (m != 0) continue;
          if (guess.radius90_mm > 0.0) {
            ++score.radii.robots;
            if (error <= guess.radius50_mm) ++score.radii.within50;
            if (error <= guess.radius90_mm) ++score.radii.within90;
          }
          if (scores_robot_probability) score.robot.add(guess.probability, right);
          every_cell_right = every_cell_right && right;
        }
      }
      if (scores_formation_probability) {
        score.formation.add(at[0]->steps[h].formation_probability, every_cell_right);
      }
      if (config.bootstrap.enabled()) {
        std::vector<double> errors(at.size());
        const DataBlock block = data_block(stream_, instant.time_s, config.bootstrap.block_s);
        for (const Scored& s : scored) {
          for (std::size_t m = 0; m < at.size(); ++m) {
            errors[m] = distance(s.guesses[m]->feed_position, s.actual->feed_position);
          }
          add_to_block(score.blocks, block, errors);
        }
      }
    }
  }
}

PositionEvaluation Evaluation::finish() {
  PositionEvaluation& result = result_;
  if (config_.bootstrap.enabled()) {
    // One set of draws for every row and horizon: the blocks any robot was scored in.
    std::vector<DataBlock> universe;
    for (const HorizonScore& score : result.all()) {
      for (const auto& [block, sums] : score.blocks) universe.push_back(block);
    }
    const BlockResamples draws(std::move(universe), config_.bootstrap);
    // The model against every other method: RowIntervals::model_ratio[m - 1] is over method m.
    std::vector<std::size_t> others;
    for (std::size_t m = 1; m < result.methods.size(); ++m) others.push_back(m);
    for (auto& row : result.rows) {
      for (HorizonScore& score : row) {
        score.intervals = bootstrap_row(score.blocks, draws, result.best_baseline(score), others);
      }
    }
  }
  return std::move(result_);
}

}  // namespace ssl_formation::evaluation::detail
