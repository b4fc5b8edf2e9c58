#include "ssl_formation/evaluate/evaluate.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <exception>
#include <fstream>
#include <memory>
#include <optional>
#include <random>

#include "ssl_formation/evaluate/html_report.hpp"
#include "ssl_formation/evaluate/log_streams.hpp"
#include "ssl_formation/evaluation/evaluation.hpp"
#include "ssl_formation/evaluation/position_evaluation.hpp"
#include "ssl_formation/files/real_log_shape.hpp"
#include "ssl_formation/files/replacing_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/training.hpp"
#include "ssl_formation/simulation/playbook.hpp"
#include "ssl_formation/simulation/simulated_events.hpp"
#include "ssl_formation/simulation/simulated_vision.hpp"

namespace ssl_formation::evaluate {

namespace ev = ssl_formation::evaluation;

namespace {

using Streams = std::vector<ev::EventStream>;

// A simulation, kept in memory for as many replays as asked.
ev::EventStream in_memory(RecordedMatch match) {
  return [match = std::make_shared<const RecordedMatch>(std::move(match))](MatchEventSink& sink) {
    match->replay(sink);
  };
}

// Hands every event on to `sink`, counting the vision packets.
class VisionCount final : public MatchEventSink {
 public:
  explicit VisionCount(MatchEventSink& sink) : sink_(sink) {}
  void on_event(const MatchEvent& event) override {
    if (event.kind == MatchEventKind::vision) ++packets_;
    sink_.on_event(event);
  }
  void start_new_stream() override { sink_.start_new_stream(); }
  std::size_t packets() const { return packets_; }

 private:
  MatchEventSink& sink_;
  std::size_t packets_ = 0;
};

// The paper's simulated opponent (no referee): one formation every 2 s of data time.
RecordedMatch paper_simulation(const EvaluateOptions& options, std::uint64_t seed, int formations) {
  sim::SimulationConfig config;
  config.seed = seed;
  config.jitter_mm = options.jitter_mm;
  config.cameras = options.cameras;
  return sim::record_paper_simulation(config, formations);
}

// A simulated match with its game controller: 60 frames a second of a team running a playbook.
RecordedMatch match_simulation(const EvaluateOptions& options, std::uint64_t seed, double seconds) {
  sim::MatchSimulationConfig config;
  config.seed = seed;
  Result<sim::Playbook> playbook = sim::builtin_or_file_playbook(options.playbook);
  if (!playbook) throw app::UsageError("--playbook: " + playbook.error().message);
  config.playbook = std::move(*playbook);
  config.jitter_mm = options.jitter_mm;
  config.cameras = options.cameras;
  sim::GameControllerConfig game;
  game.seed = seed;
  game.random_stoppages = false;  // the match calls its own stoppages
  config.game = game;
  return sim::record_match_simulation(std::move(config), seconds);
}

// A CSV file in -o/--output's folder, or nowhere without one: tables are printed either way. It
// replaces an earlier file of the name only when the run gets to its end: leaving its scope
// while an exception unwinds (a failed run) leaves the earlier file as it was.
class CsvFile {
 public:
  CsvFile(const EvaluateOptions& options, const std::string& name) {
    if (options.output_dir.empty()) return;
    const std::filesystem::path path = std::filesystem::path(options.output_dir) / name;
    app::check_outputs_free({path.string()}, options.overwrite);
    std::filesystem::create_directories(path.parent_path());
    file_.emplace(path);
    spdlog::info("writing {}", path.string());
  }
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  ~CsvFile() {
    if (!file_ || std::uncaught_exceptions() > unwinding_) return;  // discarded by file_
    try {
      file_->commit();
    } catch (const std::exception& error) {
      spdlog::error("{}", error.what());
    }
  }
  template <typename T>
  CsvFile& operator<<(const T& value) {
    if (file_) file_->stream() << value;
    return *this;
  }

 private:
  std::optional<ReplacingFile> file_;
  int unwinding_ = std::uncaught_exceptions();
};

// --write-samples: every robot as it was scored (ev::ScoredSample), a line each, for cutting the
// tables another way (by how the robot moved, by robot, by time). Positions in the feed's
// coordinates, mm. `chain` tells the sections apart: 0 for a horizon's own model (--horizons), 1
// for the chain of --step steps, whose first step may be a horizon of its own too.
class SampleFile {
 public:
  // `pooled`: the sections score the model's pooled ablation too (PositionEvaluationConfig::
  // pooled_ablation with the motion model), after the baselines.
  SampleFile(const std::string& path, bool pooled) : path_(path), pooled_(pooled) {
    if (path_.empty()) return;
    file_.emplace(path_);
    spdlog::info("writing every scored robot to {}", path_);
    out()
        << "grid,chain,step_s,horizon_steps,horizon_s,stream,time_s,robot_id,game_state,x_mm,y_mm,"
           "truth_x_mm,truth_y_mm,model_x_mm,model_y_mm";
    // The baselines every section scores (PositionEvaluationConfig's default), in their order.
    for (const ModelKind baseline : baseline_kinds) {
      out() << ',' << describe(baseline).name << "_x_mm," << describe(baseline).name << "_y_mm";
    }
    if (pooled_) out() << ",model_pooled_x_mm,model_pooled_y_mm";
    out() << ",model_radius50_mm,model_radius90_mm,model_stays\n";
  }
  bool enabled() const { return file_.has_value(); }
  void write(const std::string& grid, bool chain, const ev::ScoredSample& sample) {
    if (sample.forecasts->size() != 1 + baseline_kinds.size() + (pooled_ ? 1 : 0)) {
      throw std::logic_error("--write-samples: a section scored other methods than the header's");
    }
    out() << grid << (chain ? ",1" : ",0");
    put(",%g,%d,%g,%zu,%.3f,%u,", sample.step_s, sample.steps, sample.steps * sample.step_s,
        sample.stream, sample.time_s, sample.robot_id);
    out() << ev::state_row_name(ev::state_row_of(sample.phase));
    put(",%.1f,%.1f,%.1f,%.1f", sample.position.x, sample.position.y, sample.truth.x,
        sample.truth.y);
    for (const RobotPrediction* forecast : *sample.forecasts) {
      put(",%.1f,%.1f", forecast->feed_position.x, forecast->feed_position.y);
    }
    const RobotPrediction& model = *sample.forecasts->front();
    put(",%.1f,%.1f,%d\n", model.radius50_mm, model.radius90_mm, model.stays ? 1 : 0);
  }
  // Throws if anything failed to be written so far (a full disk): checked after each grid, so a
  // failed file stops the run rather than its end.
  void check() const {
    if (enabled() && !file_->good()) throw std::runtime_error("cannot write " + path_);
  }
  // The file in place of any earlier one: the run got to its end.
  void close() {
    if (enabled()) file_->commit();
  }

 private:
  std::ostream& out() { return file_->stream(); }
  // One field or a few, formatted in place (a stream's formatting of doubles was most of the
  // writing time). A line cut short would run into the next: that throws instead. (The format
  // attribute has the compiler check each call's values against its format.)
  [[gnu::format(printf, 2, 3)]] void put(const char* format, ...) {
    char buffer[256];
    std::va_list values;
    va_start(values, format);
    const int written = std::vsnprintf(buffer, sizeof buffer, format, values);
    va_end(values);
    if (written < 0 || written >= static_cast<int>(sizeof buffer)) {
      throw std::runtime_error("--write-samples: a field too long to write");
    }
    out().write(buffer, written);
  }

  std::string path_;
  bool pooled_ = false;
  std::optional<ReplacingFile> file_;
};

}  // namespace

// ---- paper
// ---------------------------------------------------------------------------------------

int run_paper(const EvaluateOptions& options) {
  // The paper's protocol is the paper's model on step sampling, whatever --model says.
  app::ModelOptions paper = options.model;
  paper.model = "paper";
  SamplerConfig config = paper.sampler_config();
  const auto started = std::chrono::steady_clock::now();
  // The paper's protocol trains one table, on the logs one after the other (each its own
  // stream) or on the paper's simulated opponent.
  Streams training_data;
  if (options.train_logs.empty()) {
    training_data.push_back(
        in_memory(paper_simulation(options, options.seed, options.train_formations)));
  } else {
    for (const std::string& log : options.train_logs) {
      training_data.push_back(LogFile(log).stream());
    }
  }
  Training training(config, TransitionTable(config.grid));
  VisionCount counted(training);
  for (const ev::EventStream& stream : training_data) {
    counted.start_new_stream();
    stream(counted);
  }
  const std::size_t packets = counted.packets();
  const FieldSize field = training.sampler().field();
  const std::uint64_t training_samples = training.samples();
  const StoredTable stored = training.stored_table();
  const TransitionTable& table = stored.table;

  std::vector<ev::PlayStates> plays;
  for (int p = 0; p < sim::play_count; ++p) {
    std::vector<std::vector<Point>> positions;
    for (int f = 0; f < sim::formations_per_play; ++f) {
      const auto& team = sim::play_formation(p, f);
      positions.emplace_back(team.begin(), team.end());
    }
    plays.push_back(ev::play_states(table.codec(), field, positions));
  }

  // The test formations: the paper's random formations, every robot anywhere, velocity 0.
  std::mt19937_64 random(options.test_seed);
  std::uniform_real_distribution<double> x(-field.length_mm / 2, field.length_mm / 2);
  std::uniform_real_distribution<double> y(-field.width_mm / 2, field.width_mm / 2);
  ev::PaperSummary summary;
  CsvFile csv(options, "paper-running-averages.csv");
  csv << "test,count_per_play,distance_per_play,count_per_formation,distance_per_formation,"
         "confidence_1,confidence_2\n";
  for (int t = 0; t < options.tests; ++t) {
    std::vector<FormationRobot> robots(sim::robots_per_team);
    for (std::size_t id = 0; id < robots.size(); ++id) {
      robots[id].robot_id = static_cast<std::uint32_t>(id);
      robots[id].position = Point{x(random), y(random)};
    }
    const Formation formation =
        FormationSampler::build_formation(table.codec(), field, robots, nullptr);
    ev::accumulate(summary, ev::run_paper_test(table, robot_states(formation), plays));
    csv << summary.tests << ',' << summary.count_per_play << ',' << summary.distance_per_play << ','
        << summary.count_per_formation << ',' << summary.distance_per_formation << ','
        << summary.mean_confidence[0] << ',' << summary.mean_confidence[1] << '\n';
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  std::printf(
      "Paper protocol (§6.1): trained on %llu formations (%zu packets, %llu transitions), "
      "%d tests, grid %s\n",
      static_cast<unsigned long long>(training_samples), packets,
      static_cast<unsigned long long>(table.transitions()), summary.tests,
      config.grid.to_string().c_str());
  std::printf("%-28s %14s %14s %14s %14s\n", "", "per play", "paper", "per formation", "paper");
  std::printf("%-28s %14.4f %14.4f %14.4f %14.4f\n", "count similarity measure",
              summary.count_per_play, 16.6826, summary.count_per_formation, 5.5608);
  std::printf("%-28s %14.4f %14.4f %14.4f %14.4f\n", "distance similarity measure",
              summary.distance_per_play, 21.9680, summary.distance_per_formation, 7.3226);
  std::printf("average confidence: 1st predicted formation %.6f, 2nd %.6f\n",
              summary.mean_confidence[0], summary.mean_confidence[1]);
  std::printf("took %.2f s\n", seconds);
  return 0;
}

// ---- holdout
// ---------------------------------------------------------------------------------------

namespace {

// The training and test streams the options describe: logs (each its own stream, split in time
// with --split), or simulations of two seeds.
std::pair<Streams, Streams> holdout_streams(const EvaluateOptions& options,
                                            const std::string& simulation) {
  Streams train;
  Streams test;
  if (options.tune && !options.test_logs.empty()) {
    throw app::UsageError(
        "--tune reads only the first --split of each --train-log; --test-log "
        "files are reported data (docs/tuning.md), not tuning data");
  }
  if (options.split > 0.0) {
    if (options.train_logs.empty()) throw app::UsageError("--split needs --train-log");
    // As RecordedMatch::split cuts a match: after the first `split` of its vision packets.
    const auto cut = [&](std::uint64_t vision_events) {
      return static_cast<std::uint64_t>(std::clamp(options.split, 0.0, 1.0) *
                                        static_cast<double>(vision_events));
    };
    for (const std::string& log : options.train_logs) {
      const LogFile file(log);
      const std::uint64_t head = cut(file.vision_events());
      if (options.tune) {
        // The inner split (docs/tuning.md): the reported part, after `head`, is left unread.
        const std::uint64_t inner = cut(head);
        train.push_back(file.stream({0, inner}));
        test.push_back(file.stream({inner, head}));
      } else {
        train.push_back(file.stream({0, head}));
        test.push_back(file.stream({head}));
      }
    }
    if (options.tune) {
      std::printf(
          "Tuning split: trained on the first %.4g of each log, tested on the next %.4g; "
          "the last %.4g, which reports, is not scored.\n",
          options.split * options.split, options.split * (1.0 - options.split),
          1.0 - options.split);
    }
  } else if (options.tune) {
    throw app::UsageError(
        "--tune is for --split F: it trains on the first F of each log's first F "
        "and tests on the rest of that, leaving the reported part unread");
  } else if (!options.train_logs.empty() && options.test_logs.empty()) {
    throw app::UsageError(
        "--train-log needs --test-log (other logs to test on) or --split F (the rest of each "
        "log after its first F): a model is only judged on data it was not trained on");
  } else {
    for (const std::string& log : options.train_logs) train.push_back(LogFile(log).stream());
  }
  for (const std::string& log : options.test_logs) test.push_back(LogFile(log).stream());
  if (train.empty() != test.empty()) {
    throw app::UsageError("give both --train-log and --test-log, or neither (a simulation)");
  }
  if (train.empty()) {
    if (simulation == "paper") {
      train.push_back(in_memory(paper_simulation(options, options.seed, options.train_formations)));
      test.push_back(
          in_memory(paper_simulation(options, options.test_seed, options.test_formations)));
    } else {
      train.push_back(in_memory(match_simulation(options, options.seed, options.train_seconds)));
      test.push_back(in_memory(match_simulation(options, options.test_seed, options.test_seconds)));
    }
  }
  return {std::move(train), std::move(test)};
}

// One configuration's evaluation: its horizons, from `steps` steps of `step_s`.
struct Section {
  double step_s = 0.0;
  ev::PositionEvaluation evaluation;
};

struct GridReport {
  Grid grid{3, 2};
  std::vector<Section> sections;  // one per --horizons entry, then the chains of --step
  double prediction_us = 0.0;     // mean two-step prediction time of the chains' table
  ReportSamples chain_samples;    // the last section's robots, for --report
};

// Two-step predictions of the paper's model from the test formations, timed.
double time_predictions(const TransitionTable& table, const Streams& test,
                        const SamplerConfig& config) {
  constexpr std::size_t timed = 5000;
  std::vector<std::vector<RobotStateById>> inputs;
  FormationSampler sampler(config, [&](const FormationSample& sample) {
    if (inputs.size() < timed) inputs.push_back(robot_states(sample.formation));
  });
  struct Feed final : MatchEventSink {
    FormationSampler& sampler;
    const std::vector<std::vector<RobotStateById>>& inputs;
    Feed(FormationSampler& s, const std::vector<std::vector<RobotStateById>>& i)
        : sampler(s), inputs(i) {}
    void on_event(const MatchEvent& event) override {
      // Past the formations timed, the rest of the log is only read.
      if (event.kind == MatchEventKind::vision && inputs.size() < timed) sampler.add(*event.frame);
    }
    void start_new_stream() override { sampler.start_new_stream(); }
  } feed(sampler, inputs);
  for (const ev::EventStream& stream : test) {
    feed.start_new_stream();
    stream(feed);
  }
  Prediction prediction;
  const auto start = std::chrono::steady_clock::now();
  std::size_t runs = 0;
  for (int pass = 0; pass < 20 && !inputs.empty(); ++pass) {
    for (const auto& input : inputs) {
      predict(table, input, 2, prediction);
      ++runs;
    }
  }
  const double elapsed =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  return runs ? elapsed / static_cast<double>(runs) : 0.0;
}

// `prior`: every team's table (--prior-table), loaded once for every grid.
GridReport holdout_for_grid(const EvaluateOptions& options, const std::string& grid,
                            const Streams& train, const Streams& test,
                            const std::shared_ptr<const MotionTable>& prior, SampleFile& samples) {
  app::ModelOptions model = options.model;
  model.grid = grid;
  const SamplerConfig base = model.sampler_config();
  GridReport report;
  report.grid = base.grid;
  // A prior serves the sections of its own step (the chained steps, and the single horizon equal
  // to it): a table's rows are learned for one step.
  std::vector<ev::PositionEvaluationConfig> configs;
  const auto section = [&](double step_s, int steps, bool chain) {
    ev::PositionEvaluationConfig config;
    config.sampler = base;
    config.sampler.step_s = step_s;
    config.steps = steps;
    config.velocity_window_s = options.velocity_window_s;
    config.model = model.parsed_model();
    config.recalibration = app::recalibration_settings(options.recalibration_half_life_s);
    config.rules =
        MatchRules{model.opponent_choice(), app::parsed_learn_during(options.learn_during)};
    config.tracked_vision = options.network.tracked();
    if (prior && std::abs(prior->config().step_s - step_s) < 1e-9) config.prior_table = prior;
    config.table_budget = app::table_budget_option(options.max_table_mb);
    config.bootstrap.resamples = options.bootstrap;
    config.bootstrap.block_s = options.bootstrap_block_s;
    const bool report_this = chain && !options.report.empty();
    if (samples.enabled() || report_this) {
      config.on_sample = [&samples, chain, report_this, &report,
                          name = base.grid.to_string()](const ev::ScoredSample& s) {
        if (samples.enabled()) samples.write(name, chain, s);
        if (report_this) report.chain_samples.add(s);
      };
    }
    configs.push_back(std::move(config));
  };
  for (const double horizon_s : options.horizons) section(horizon_s, 1, false);
  section(base.step_s, options.chain_steps, true);
  // Every section over one read of each stream.
  std::vector<ev::PositionEvaluation> evaluations = ev::evaluate_positions(configs, train, test);
  for (std::size_t i = 0; i < configs.size(); ++i) {
    report.sections.push_back({configs[i].sampler.step_s, std::move(evaluations[i])});
  }
  if (const auto& table = report.sections.back().evaluation.table) {
    report.prediction_us = time_predictions(table->table, test, base);
  }
  return report;
}

const char* quantity_name(bool robot) { return robot ? "robot" : "formation"; }

// How a method is named in the tables: the model as "model", the baselines by their labels.
std::string method_label(const ev::PositionEvaluation& evaluation, std::size_t m) {
  return evaluation.labels.at(m);
}

// Every row of game state and step of every section that scored a robot, in the report's order:
// visit(evaluation, row, step index, score).
template <typename Visit>
void for_each_scored_row(const GridReport& report, Visit&& visit) {
  for (const Section& section : report.sections) {
    const ev::PositionEvaluation& evaluation = section.evaluation;
    for (const std::size_t row : evaluation.reported_rows()) {
      for (std::size_t h = 0; h < evaluation.rows[row].size(); ++h) {
        const ev::HorizonScore& score = evaluation.rows[row][h];
        if (score.methods.front().cells.robots > 0) visit(evaluation, row, h, score);
      }
    }
  }
}

// "6.1% [4.2, 9.0]": how far below 1 a ratio of mean errors is, in percent, with the interval
// of the ratio (low and high swap) when there is one.
std::string margin_text(double ratio, const ev::Interval* interval) {
  char text[64];
  if (interval) {
    std::snprintf(text, sizeof text, "%.1f%% [%.1f, %.1f]", 100.0 * (1.0 - ratio),
                  100.0 * (1.0 - interval->high), 100.0 * (1.0 - interval->low));
  } else {
    std::snprintf(text, sizeof text, "%.1f%%", 100.0 * (1.0 - ratio));
  }
  return text;
}

bool has_intervals(const ev::HorizonScore& score) {
  return score.intervals.mean.size() == score.methods.size();
}

// "[145.2, 151.0]"; a row over too few blocks for one, "(3 blocks)"; "" without the bootstrap.
std::string interval_text(const ev::HorizonScore& score, std::size_t m, bool bootstrap) {
  if (!bootstrap) return "";
  char text[64];
  if (!has_intervals(score)) {
    std::snprintf(text, sizeof text, "(%zu block%s)", score.intervals.blocks,
                  score.intervals.blocks == 1 ? "" : "s");
  } else {
    const ev::Interval& i = score.intervals.mean[m];
    std::snprintf(text, sizeof text, "[%.1f, %.1f]", i.low, i.high);
  }
  return text;
}

// The model (or the scored predictions) against the best baseline of each row, with the
// intervals of their ratio.
void print_ratios(const GridReport& report, const EvaluateOptions& options) {
  const ev::PositionEvaluation& first = report.sections.front().evaluation;
  const std::string scored = method_label(first, 0);  // "model" or "predictions"
  std::printf(
      "The %s against the best baseline of each row: mean error over the best's, 95%% "
      "intervals from %d resamples of %.0f s blocks (none for a row over fewer than %zu "
      "blocks):\n",
      scored.c_str(), options.bootstrap, options.bootstrap_block_s,
      ev::BootstrapConfig{}.min_blocks);
  // The model's first ablation (the pooled model), if the evaluation ran one.
  const bool has_ablation = first.baselines_end < first.methods.size();
  const std::size_t ablation = first.baselines_end;
  std::printf("%9s %5s %-24s %7s %-30s %12s %18s %20s", "horizon", "steps", "game state", "blocks",
              "best baseline", (scored + "/best").c_str(), "95% interval",
              (scored + " below best").c_str());
  if (has_ablation) {
    std::printf(" %26s", ("model below '" + method_label(first, ablation) + "'").c_str());
  }
  std::printf("\n");
  for_each_scored_row(report, [&](const ev::PositionEvaluation& evaluation, std::size_t row,
                                  std::size_t h, const ev::HorizonScore& score) {
    const std::optional<std::size_t> best = evaluation.best_baseline(score);
    if (!best) return;
    const double ratio = score.methods[0].error.mean() / score.methods[*best].error.mean();
    char range[64] = "";
    const ev::Interval* interval = nullptr;
    if (!score.intervals.ratio.empty()) {
      interval = &score.intervals.ratio[0];
      std::snprintf(range, sizeof range, "[%.3f, %.3f]", interval->low, interval->high);
    }
    std::printf("%7.2f s %5zu %-24s %7zu %-30s %12.3f %18s %20s", score.horizon_s, h + 1,
                std::string(ev::state_row_name(row)).c_str(), score.intervals.blocks,
                method_label(evaluation, *best).c_str(), ratio, range,
                margin_text(ratio, interval).c_str());
    if (has_ablation && ablation < score.methods.size()) {
      const double over = score.methods[0].error.mean() / score.methods[ablation].error.mean();
      const bool drawn = score.intervals.model_ratio.size() >= ablation;
      std::printf(
          " %26s",
          margin_text(over, drawn ? &score.intervals.model_ratio[ablation - 1] : nullptr).c_str());
    }
    std::printf("\n");
  });
}

void print_calibration(const GridReport& report);
void print_radii(const GridReport& report);

void print_holdout(const GridReport& report, const SamplerConfig& base,
                   const EvaluateOptions& options) {
  const ev::PositionEvaluation& chains = report.sections.back().evaluation;
  if (chains.labels.front() == "predictions") {
    std::printf(
        "Scored predictions from %s against %s, grid %s: %llu formations of the log; "
        "the damped baselines fitted on %llu formations\n",
        options.predictions.c_str(), options.log.c_str(), report.grid.to_string().c_str(),
        static_cast<unsigned long long>(chains.test_formations),
        static_cast<unsigned long long>(chains.train_formations));
  } else {
    std::printf(
        "Held-out evaluation, grid %s, %s sampling: %llu test formations; the chains' table: "
        "%llu transitions from %llu formations\n",
        report.grid.to_string().c_str(), std::string(to_string(base.sampling)).c_str(),
        static_cast<unsigned long long>(chains.test_formations),
        static_cast<unsigned long long>(chains.transitions),
        static_cast<unsigned long long>(chains.train_formations));
  }
  if (chains.feed_problem) std::printf("warning: %s\n", chains.feed_problem->c_str());
  if (!chains.test_has_referee) {
    std::printf(
        "The test streams carry no referee messages: every instant counts as running "
        "play, and only the rows 'all' and 'running' are given.\n");
  }
  const bool intervals = options.bootstrap > 0;
  std::printf("%9s %5s %-30s %11s %11s %9s %9s %s%9s %9s %9s\n", "horizon", "steps", "method",
              "exact state", "exact cell", "cells off", "mean mm",
              intervals ? "     95% interval " : "", "median mm", "p90 mm", "robots");
  for (const Section& section : report.sections) {
    const ev::PositionEvaluation& evaluation = section.evaluation;
    for (std::size_t h = 0; h < evaluation.all().size(); ++h) {
      const ev::HorizonScore& score = evaluation.all()[h];
      for (std::size_t m = 0; m < score.methods.size(); ++m) {
        const ev::Accuracy& a = score.methods[m].cells;
        const ev::ErrorStats& e = score.methods[m].error;
        char interval[64] = "";
        if (intervals) {
          std::snprintf(interval, sizeof interval, " %18s",
                        interval_text(score, m, intervals).c_str());
        }
        // What the scored file does not state (its states, its cells) is shown as '-'.
        char state[32] = "          -";
        char cell[32] = "          -";
        char cells_off[32] = "        -";
        if (m != 0 || evaluation.model_states_states) {
          std::snprintf(state, sizeof state, "%10.2f%%", 100.0 * a.state_accuracy());
        }
        if (m != 0 || evaluation.model_states_cells) {
          std::snprintf(cell, sizeof cell, "%10.2f%%", 100.0 * a.cell_accuracy());
          std::snprintf(cells_off, sizeof cells_off, "%9.3f", a.mean_distance());
        }
        std::printf("%7.2f s %5zu %-30s %s %s %s %9.1f%s %9.1f %9.1f %9llu\n", score.horizon_s,
                    h + 1, method_label(evaluation, m).c_str(), state, cell, cells_off, e.mean(),
                    interval, e.median(), e.percentile(90),
                    static_cast<unsigned long long>(a.robots));
      }
    }
  }
  // By phase of the game: the mean error of every method, for the rows with anything in them.
  std::printf("Mean error (mm) by phase of the game%s:\n%9s %5s %-24s %9s",
              intervals ? ", with its 95% interval" : "", "horizon", "steps", "game state",
              "robots");
  const int width = intervals ? 28 : 12;
  for (std::size_t m = 0; m < chains.methods.size(); ++m) {
    std::printf(" %*.*s", width, width, method_label(chains, m).c_str());
  }
  std::printf("\n");
  for_each_scored_row(report, [&](const ev::PositionEvaluation&, std::size_t row, std::size_t h,
                                  const ev::HorizonScore& score) {
    std::printf("%7.2f s %5zu %-24s %9llu", score.horizon_s, h + 1,
                std::string(ev::state_row_name(row)).c_str(),
                static_cast<unsigned long long>(score.methods.front().cells.robots));
    for (std::size_t m = 0; m < score.methods.size(); ++m) {
      char cell[96];
      std::snprintf(cell, sizeof cell, "%.1f%s%s", score.methods[m].error.mean(),
                    intervals ? " " : "", interval_text(score, m, intervals).c_str());
      std::printf(" %*s", width, cell);
    }
    std::printf("\n");
  });
  if (intervals) print_ratios(report, options);
  print_calibration(report);
  print_radii(report);
}

// The calibration of the probabilities stated (none: nothing printed, as for a file of
// predictions without them).
void print_calibration(const GridReport& report) {
  const bool stated =
      std::any_of(report.sections.begin(), report.sections.end(), [](const Section& section) {
        return std::any_of(section.evaluation.all().begin(), section.evaluation.all().end(),
                           [](const ev::HorizonScore& score) { return score.robot.n > 0; });
      });
  if (!stated) return;
  const bool file = method_label(report.sections.front().evaluation, 0) == "predictions";
  std::printf("Calibration of the %s probabilities (10 equal bins):\n",
              file ? "file's" : "model's");
  std::printf("%9s %5s %-10s %9s %9s %12s\n", "horizon", "steps", "quantity", "Brier", "ECE",
              "predictions");
  for (const Section& section : report.sections) {
    for (std::size_t h = 0; h < section.evaluation.all().size(); ++h) {
      const ev::HorizonScore& score = section.evaluation.all()[h];
      for (const bool robot : {true, false}) {
        const ev::Calibration& c = robot ? score.robot : score.formation;
        std::printf("%7.2f s %5zu %-10s %9.4f %9.4f %12llu\n", score.horizon_s, h + 1,
                    quantity_name(robot), c.brier(), ev::expected_calibration_error(c),
                    static_cast<unsigned long long>(c.n));
      }
    }
  }
}

// How often the robots were within the radii stated (none: nothing printed).
void print_radii(const GridReport& report) {
  if (report.sections.front().evaluation.all().front().radii.robots == 0) return;
  std::printf("The model's radii: how often the robot was within them (aim: 50%% and 90%%):\n");
  std::printf("%9s %5s %12s %12s %12s\n", "horizon", "steps", "within r50", "within r90", "robots");
  for (const Section& section : report.sections) {
    for (std::size_t h = 0; h < section.evaluation.all().size(); ++h) {
      const ev::HorizonScore& score = section.evaluation.all()[h];
      std::printf("%7.2f s %5zu %11.1f%% %11.1f%% %12llu\n", score.horizon_s, h + 1,
                  100.0 * score.radii.share50(), 100.0 * score.radii.share90(),
                  static_cast<unsigned long long>(score.radii.robots));
    }
  }
}

void write_holdout_csv(CsvFile& accuracy, CsvFile& calibration, CsvFile& reliability,
                       const GridReport& report) {
  const std::string grid = report.grid.to_string();
  for (const Section& section : report.sections) {
    const ev::PositionEvaluation& evaluation = section.evaluation;
    for (const std::size_t row : evaluation.reported_rows()) {
      const std::string state(ev::state_row_name(row));
      for (std::size_t h = 0; h < evaluation.rows[row].size(); ++h) {
        const ev::HorizonScore& score = evaluation.rows[row][h];
        for (std::size_t m = 0; m < score.methods.size(); ++m) {
          const ev::Accuracy& a = score.methods[m].cells;
          const ev::ErrorStats& e = score.methods[m].error;
          accuracy << grid << ',' << h + 1 << ',' << score.horizon_s << ',' << state << ','
                   << method_label(evaluation, m) << ',';
          // Empty where the scored file states no states or cells.
          if (m != 0 || evaluation.model_states_states) accuracy << a.state_accuracy();
          accuracy << ',';
          if (m != 0 || evaluation.model_states_cells) {
            accuracy << a.cell_accuracy() << ',' << a.mean_distance();
          } else {
            accuracy << ',';
          }
          accuracy << ',' << e.mean() << ',' << e.median() << ',' << e.percentile(90) << ','
                   << a.robots;
          // The intervals, empty without --bootstrap; the ratio is this method's mean over the
          // best baseline's (1 for the best baseline itself).
          const ev::RowIntervals& intervals = score.intervals;
          if (has_intervals(score)) {
            accuracy << ',' << intervals.mean[m].low << ',' << intervals.mean[m].high;
          } else {
            accuracy << ",,";
          }
          const std::optional<std::size_t> best = evaluation.best_baseline(score);
          if (best && a.robots > 0) {
            accuracy << ',' << method_label(evaluation, *best) << ','
                     << e.mean() / score.methods[*best].error.mean();
          } else {
            accuracy << ",,";
          }
          if (!intervals.ratio.empty()) {
            accuracy << ',' << intervals.ratio[m].low << ',' << intervals.ratio[m].high;
          } else {
            accuracy << ",,";
          }
          // The model's mean over this method's (1 on the model's own row).
          if (a.robots > 0 && e.mean() > 0.0) {
            accuracy << ',' << score.methods[0].error.mean() / e.mean();
          } else {
            accuracy << ',';
          }
          if (m == 0 && has_intervals(score)) {
            accuracy << ",1,1";
          } else if (m > 0 && intervals.model_ratio.size() >= m) {
            accuracy << ',' << intervals.model_ratio[m - 1].low << ','
                     << intervals.model_ratio[m - 1].high;
          } else {
            accuracy << ",,";
          }
          accuracy << ',' << intervals.blocks << '\n';
        }
        for (const bool robot : {true, false}) {
          const ev::Calibration& c = robot ? score.robot : score.formation;
          calibration << grid << ',' << h + 1 << ',' << score.horizon_s << ',' << state << ",model,"
                      << quantity_name(robot) << ',' << c.brier() << ','
                      << ev::expected_calibration_error(c) << ',' << c.n << ','
                      << score.radii.share50() << ',' << score.radii.share90() << '\n';
          for (std::size_t b = 0; b < c.bin_count.size(); ++b) {
            const auto n = static_cast<double>(c.bin_count[b]);
            reliability << grid << ',' << h + 1 << ',' << score.horizon_s << ',' << state << ','
                        << quantity_name(robot) << ',' << b << ',' << c.bin_count[b] << ','
                        << (n > 0 ? c.bin_confidence[b] / n : 0.0) << ','
                        << (n > 0 ? static_cast<double>(c.bin_hits[b]) / n : 0.0) << '\n';
          }
        }
      }
    }
  }
}

// The report's three CSV files (accuracy, calibration, reliability) with their headers, in
// -o/--output's folder with `prefix` ("holdout-", "grid-sweep-", "score-").
struct ReportFiles {
  ReportFiles(const EvaluateOptions& options, const std::string& prefix)
      : accuracy(options, prefix + "accuracy.csv"),
        calibration(options, prefix + "calibration.csv"),
        reliability(options, prefix + "reliability.csv") {
    accuracy << "grid,horizon_steps,horizon_s,game_state,method,state_accuracy,cell_accuracy,"
                "mean_cell_distance,mean_error_mm,median_error_mm,p90_error_mm,robots,"
                "mean_error_mm_ci_low,mean_error_mm_ci_high,best_baseline,ratio_to_best_baseline,"
                "ratio_ci_low,ratio_ci_high,model_ratio_to_method,model_ratio_ci_low,"
                "model_ratio_ci_high,bootstrap_blocks\n";
    calibration << "grid,horizon_steps,horizon_s,game_state,method,quantity,brier,ece,"
                   "predictions,within_radius_50,within_radius_90\n";
    reliability << "grid,horizon_steps,horizon_s,game_state,quantity,bin,count,mean_confidence,"
                   "observed_frequency\n";
  }
  CsvFile accuracy;
  CsvFile calibration;
  CsvFile reliability;
};

// Stops before any work if --report's path cannot be written.
void check_report_path(const EvaluateOptions& options) {
  if (options.report.empty()) return;
  const bool existed = std::filesystem::exists(options.report);
  {
    std::ofstream probe(options.report, std::ios::app);
    if (!probe) throw std::runtime_error("cannot write the report " + options.report);
  }
  if (!existed) std::filesystem::remove(options.report);  // the probe leaves nothing behind
}

// --report's page for one section (the predictor's chain, or score's file).
void write_report(const EvaluateOptions& options, const std::string& title, const Grid& grid,
                  const Section& section, const ReportSamples& samples) {
  if (options.report.empty()) return;
  ReportInput input;
  input.title = title;
  input.command = options.command_line;
  input.grid = grid.to_string();
  input.step_s = section.step_s;
  input.evaluation = &section.evaluation;
  input.samples = &samples;
  input.bootstrap = options.bootstrap;
  input.bootstrap_block_s = options.bootstrap_block_s;
  write_html_report(options.report, input);
  spdlog::info("wrote the report {}", options.report);
}

}  // namespace

std::vector<double> parse_horizons(const std::string& text) {
  std::vector<double> horizons;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    double value = 0.0;
    const auto [rest, error] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || error != std::errc() || rest != item.data() + item.size() ||
        !(value > 0.0) || value > 600.0) {
      throw app::UsageError(
          "--horizons takes positive seconds separated by commas (e.g. "
          "0.2,0.5,1,2), not '" +
          text + "'");
    }
    horizons.push_back(value);
    begin = end + 1;
  }
  return horizons;
}

int run_holdout(const EvaluateOptions& options, const std::vector<std::string>& grids) {
  if (options.chain_steps < 1 || options.chain_steps > 10) {
    throw app::UsageError("--chain-steps must be 1 to 10");
  }
  if (!(options.velocity_window_s > 0.0)) {
    throw app::UsageError("--velocity-window must be a positive number of seconds");
  }
  if (!(options.train_seconds > 0.0) || !(options.test_seconds > 0.0)) {
    throw app::UsageError("--train-seconds and --test-seconds must be positive");
  }
  const SamplerConfig base = options.model.sampler_config();
  (void)app::parsed_learn_during(options.learn_during);
  std::string simulation = options.simulation;
  if (simulation == "auto") {
    simulation = describe(options.model.parsed_model()).needs_every_frame ? "match" : "paper";
  }
  if (simulation != "paper" && simulation != "match") {
    throw app::UsageError("--simulation must be auto, paper or match, not '" + options.simulation +
                          "'");
  }
  // Before any work: a path it cannot write stops it.
  SampleFile samples(options.write_samples, options.model.parsed_model() == ModelKind::motion);
  check_report_path(options);
  if (!options.report.empty() && grids.size() > 1) {
    throw app::UsageError("--report is for holdout (one grid), not grid-sweep");
  }
  const auto [train, test] = holdout_streams(options, simulation);
  const std::string prefix = grids.size() > 1 ? "grid-sweep-" : "holdout-";
  ReportFiles files(options, prefix);
  CsvFile& accuracy = files.accuracy;
  CsvFile& calibration = files.calibration;
  CsvFile& reliability = files.reliability;
  const std::shared_ptr<const MotionTable> prior =
      app::loaded_prior_table(options.prior_table, options.model.step());
  std::vector<GridReport> reports;
  for (const std::string& grid : grids) {
    reports.push_back(holdout_for_grid(options, grid, train, test, prior, samples));
    print_holdout(reports.back(), base, options);
    write_holdout_csv(accuracy, calibration, reliability, reports.back());
    write_report(options, "ssl-formation: held-out evaluation, the predictor's steps",
                 reports.back().grid, reports.back().sections.back(), reports.back().chain_samples);
    samples.check();
    std::printf("\n");
  }
  if (grids.size() > 1) {
    CsvFile sweep(options, "grid-sweep.csv");
    sweep << "grid,states,transitions,table_memory_bytes,prediction_us,model_cell_accuracy_h1,"
             "persistence_cell_accuracy_h1,constant_velocity_cell_accuracy_h1,"
             "damped_constant_velocity_cell_accuracy_h1,model_mean_error_mm_h1,"
             "model_mean_error_mm_h1_ci_low,model_mean_error_mm_h1_ci_high\n";
    std::printf("Grid sweep (one step of --step)\n%-6s %12s %12s %14s %14s %12s %12s %12s\n",
                "grid", "states", "transitions", "table memory", "predict 2 (us)", "model cell",
                "persist cell", "const-v cell");
    for (const GridReport& r : reports) {
      const ev::PositionEvaluation& chains = r.sections.back().evaluation;
      const ev::HorizonScore& h1 = chains.all().front();
      const auto cell = [&](ModelKind kind) {
        const auto it = std::find(chains.methods.begin() + 1, chains.methods.end(), kind);
        if (it == chains.methods.end()) return 0.0;
        return h1.methods[static_cast<std::size_t>(it - chains.methods.begin())]
            .cells.cell_accuracy();
      };
      const StateCodec codec(r.grid);
      std::printf("%-6s %12u %12llu %11.1f KiB %14.3f %11.2f%% %11.2f%% %11.2f%%\n",
                  r.grid.to_string().c_str(), codec.state_count(),
                  static_cast<unsigned long long>(chains.transitions),
                  static_cast<double>(chains.table_memory_bytes) / 1024.0, r.prediction_us,
                  100 * h1.methods[0].cells.cell_accuracy(), 100 * cell(ModelKind::persistence),
                  100 * cell(ModelKind::constant_velocity));
      sweep << r.grid.to_string() << ',' << codec.state_count() << ',' << chains.transitions << ','
            << chains.table_memory_bytes << ',' << r.prediction_us << ','
            << h1.methods[0].cells.cell_accuracy() << ',' << cell(ModelKind::persistence) << ','
            << cell(ModelKind::constant_velocity) << ','
            << cell(ModelKind::damped_constant_velocity) << ',' << h1.methods[0].error.mean();
      if (has_intervals(h1)) {
        sweep << ',' << h1.intervals.mean[0].low << ',' << h1.intervals.mean[0].high << '\n';
      } else {
        sweep << ",,\n";
      }
    }
  }
  samples.close();
  return 0;
}

// ---- score

// A predictor's first step puts most robots in their cell (the paper's 3x2 grid: above 90% at
// 0.5 s; persistence alone does as well): below this share the cells are not the log's.
constexpr double low_cell_share = 0.05;

int run_score(const EvaluateOptions& options) {
  if (options.log.empty() || options.predictions.empty()) {
    throw app::UsageError(
        "score needs --from-log (the recorded match) and --predictions (a CSV of "
        "ssl-predictor --from-log's columns for that log)");
  }
  if (!options.test_logs.empty() || options.split > 0.0) {
    throw app::UsageError("score takes one --from-log; --test-log and --split are for holdout");
  }
  check_report_path(options);
  Result<RecordedPredictions> read = read_prediction_csv(options.predictions);
  if (!read) throw std::runtime_error(read.error().message);
  auto recorded = std::make_shared<const RecordedPredictions>(std::move(*read));
  app::ModelOptions model = options.model;
  // The file says its grid (a predictor's since the grid column): taken when --grid is left on
  // auto, and a --grid that disagrees is refused rather than scored as cells of another grid.
  if (recorded->grid) {
    if (model.grid == "auto") {
      model.grid = recorded->grid->to_string();
    } else if (model.parsed_grid() != *recorded->grid) {
      throw app::UsageError("the predictions were made on a " + recorded->grid->to_string() +
                            " grid (their grid column), not --grid " +
                            model.parsed_grid().to_string() + ": give --grid " +
                            recorded->grid->to_string() + " or leave --grid out");
    }
  }
  SamplerConfig sampler = model.sampler_config();
  if (recorded->has_cells) {
    for (const RecordedPrediction& instant : recorded->instants) {
      for (const PredictedStep& step : instant.prediction.steps) {
        for (const RobotPrediction& robot : step.robots) {
          if (robot.position.x < 0 || robot.position.y < 0 ||
              robot.position.x >= sampler.grid.length() ||
              robot.position.y >= sampler.grid.width()) {
            throw app::UsageError("the predictions' cells do not fit --grid " +
                                  sampler.grid.to_string() +
                                  ": give the grid the predictor ran with");
          }
        }
      }
    }
  }
  sampler.step_s = recorded->step_s;
  sampler.sampling = Sampling::frame;
  Streams test;
  test.push_back(LogFile(options.log).stream());
  Streams train;
  for (const std::string& log : options.train_logs) train.push_back(LogFile(log).stream());
  if (train.empty()) {
    std::printf(
        "No --train-log: the damped baselines' factors are fitted on the scored log "
        "itself, which favours them.\n");
    train.push_back(test.front());
  }
  ev::PositionEvaluationConfig config;
  config.sampler = sampler;
  config.steps = recorded->steps;
  config.model = ModelKind::persistence;  // samples the instants; the file predicts
  config.velocity_window_s = options.velocity_window_s;
  config.rules =
      MatchRules{model.opponent_choice(), app::parsed_learn_during(options.learn_during)};
  config.tracked_vision = options.network.tracked();
  config.bootstrap.resamples = options.bootstrap;
  config.bootstrap.block_s = options.bootstrap_block_s;
  config.recorded_predictions = recorded;
  GridReport report;
  report.grid = sampler.grid;
  if (!options.report.empty()) {
    config.on_sample = [&report](const ev::ScoredSample& s) { report.chain_samples.add(s); };
  }
  report.sections.push_back(
      {sampler.step_s, std::move(ev::evaluate_positions({config}, train, test).front())});
  std::uint64_t scored = 0;
  for (const ev::HorizonScore& score : report.sections.back().evaluation.all()) {
    scored += score.methods.front().cells.robots;
  }
  const ev::PositionEvaluation& evaluation = report.sections.back().evaluation;
  std::printf(
      "%zu of the file's %zu instants are frames of the log (within %.0f ms), which has "
      "%llu frames: a frame without a prediction is not scored, nor is a robot the file "
      "leaves out.\n",
      static_cast<std::size_t>(evaluation.recorded_matched), recorded->instants.size(),
      1000.0 * ev::recorded_time_tolerance_s,
      static_cast<unsigned long long>(evaluation.test_formations));
  if (scored == 0) {
    throw std::runtime_error("none of the " + std::to_string(recorded->instants.size()) +
                             " instants of " + options.predictions + " is a frame of " +
                             options.log +
                             " with its robots there at every horizon: is it that "
                             "log's CSV?");
  }
  // Almost no robot in its predicted cell a step later: cells of another grid, field or frame
  // than the predictor's, which the numbers alone would not show.
  if (recorded->has_cells) {
    const ev::HorizonScore& first = evaluation.all().front();
    const double in_cell = first.methods.front().cells.cell_accuracy();
    if (first.methods.front().cells.robots > 0 && in_cell < low_cell_share) {
      spdlog::warn(
          "only {:.1f}% of the robots are in their predicted cell {} s later (persistence: "
          "{:.1f}%): were the predictions made with --grid {}, this field size and this log?",
          100.0 * in_cell, first.horizon_s, 100.0 * first.methods[1].cells.cell_accuracy(),
          sampler.grid.to_string());
    }
  }
  ReportFiles files(options, "score-");
  print_holdout(report, sampler, options);
  write_holdout_csv(files.accuracy, files.calibration, files.reliability, report);
  write_report(options, "ssl-formation: predictions from " + options.predictions + " scored",
               report.grid, report.sections.back(), report.chain_samples);
  return 0;
}

// ---- as-real-log

int run_as_real_log(const EvaluateOptions& options) {
  if (options.from_log.empty() || options.write_log.empty()) {
    throw app::UsageError("as-real-log needs --from-log FILE and -o/--output FILE");
  }
  std::optional<RealLogMess> mess = parse_real_log_mess(options.mess);
  if (!mess) {
    throw app::UsageError("--mess must be none, all or a comma-separated list of " +
                          std::string(real_log_mess_names) +
                          " (noise=MM for another noise, 0 to 1000 mm), not '" + options.mess +
                          "'");
  }
  mess->seed = options.seed;
  const Result<RealLogCounts> counts =
      write_as_real_log(options.from_log, options.write_log, *mess);
  if (!counts) {
    spdlog::error("{}", counts.error().message);
    return 1;
  }
  std::printf(
      "%s: %llu vision packets over %.1f s rewritten as %llu half-field packets (camera "
      "id 0, no geometry), mess: %s, %llu ghost detections\n",
      options.write_log.c_str(), static_cast<unsigned long long>(counts->packets_read),
      counts->recording_s, static_cast<unsigned long long>(counts->packets_written),
      options.mess.c_str(), static_cast<unsigned long long>(counts->ghost_detections));
  if (counts->referee_messages > 0 && !counts->sides_given) {
    std::printf(
        "its referee does not say which half each team defends (the recording's did not): "
        "evaluate it with --opponent-attacks auto (else the opponent is taken to attack +x "
        "throughout%s)\n",
        mess->change_of_ends ? ", which is wrong after the change of ends" : "");
  }
  return 0;
}

}  // namespace ssl_formation::evaluate
