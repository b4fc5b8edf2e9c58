// ssl-predictor's daemon: the match's events through the core's PredictionPipeline, each
// prediction multicast as a FormationPrediction and printed as one readable line, and the table
// followed as the trainer replaces it. Its status and field view: predictor_status.cpp.

#include "ssl_formation/predictor/predictor_daemon.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <iostream>

#include "ssl_formation/base/state.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"

namespace ssl_formation::predictor {
namespace {

std::string prediction_interface(const PredictorOptions& options) {
  if (!options.prediction_interface.empty()) return options.prediction_interface;
  return options.network.interface == "all" ? std::string(app::default_interface)
                                            : options.network.interface;
}

// The table's folder must exist: a predictor waiting for a file that can never appear there
// would wait for ever.
void check_table_folder(const PredictorOptions& options) {
  if (!options.table_dir.empty() || !describe(options.model.parsed_model()).keeps_table) return;
  const std::filesystem::path table(options.table);
  const std::filesystem::path folder = table.has_parent_path() ? table.parent_path() : ".";
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) {
    throw app::UsageError("--table " + options.table + ": the folder " + folder.string() +
                          " does not exist; create it (ssl-trainer writes the table there) or "
                          "give another --table");
  }
}

}  // namespace

MulticastPredictionOutput::MulticastPredictionOutput(boost::asio::io_context& io,
                                                     const PredictorOptions& options)
    : sender_(io, app::parse_group_option("prediction-address", options.prediction_address),
              app::parse_interface_option(prediction_interface(options), false).address,
              options.ttl) {}

void MulticastPredictionOutput::print(std::string_view line) {
  std::cout << line << '\n' << std::flush;
}

PredictorDaemon::PredictorDaemon(boost::asio::io_context& io, const PredictorOptions& options,
                                 const PredictionConfig& config, const app::Clock& clock,
                                 PredictionOutput& output, TableFileLoader load_file)
    : options_((check_table_folder(options), options)),
      clock_(clock),
      output_(output),
      config_(config.sampler),
      pipeline_(config, [this](const PredictedFormation& predicted) { on_prediction(predicted); }),
      table_file_(table_path(config.opponent ? config.opponent->opponent_team : "")),
      field_log_(config.sampler.field, config.sampler.use_geometry),
      // Our robots are kept as long as the sampler keeps a camera live.
      ours_(opposite(config.sampler.opponent_color), config.sampler.camera_live_window_s(),
            config.sampler.clock_reset_window_s()),
      warm_up_timer_(io) {
  // Allocated now rather than wherever the first packet leaves it: every page the hot path
  // touches costs after 16 ms asleep.
  datagram_.reserve(2048);
  if (options.http_port != 0) {
    web::FieldViewOptions web_options;
    web_options.address = options.http_address;
    const bool default_port = options.http_port == PredictorOptions::http_port_default;
    web_options.port = static_cast<std::uint16_t>(default_port ? PredictorOptions::default_http_port
                                                               : options.http_port);
    web_options.any_port_if_taken = default_port;
    web_options.max_clients = static_cast<std::size_t>(options.http_max_clients);
    web_options.send_buffer_bytes = options.http_send_buffer_bytes;
    web_.emplace(io, web_options);
  }
  if (pipeline_.needs_table()) {
    // Called on the loader's thread while this one predicts: prepare_table reads only what the
    // pipeline fixed at construction.
    loader_.emplace(table_file_, config_.grid, std::move(load_file),
                    [this](std::shared_ptr<const StoredTable> table) {
                      return pipeline_.prepare_table(std::move(table));
                    });
  }
}

void PredictorDaemon::start() {
  if (web_) {
    web_->start();  // before the receivers, so a busy port fails before anything else runs
    spdlog::info("field view: open {}", web_->url());
  }
  match_log_.update(pipeline_.front_end());
  spdlog::info(
      "predicting {} steps ahead with --model {}; grid {}, step {} s, {} sampling; "
      "vision {}; referee {}",
      options_.horizon, to_string(pipeline_.config().model), config_.grid.to_string(),
      config_.step_s, to_string(config_.sampling),
      options_.network.tracked() ? "tracked " + options_.network.tracker_address
                                 : options_.network.vision_address,
      options_.network.referee_address);
  if (!pipeline_.needs_table()) {
    spdlog::info("--model {} needs no table: predicting from the first formation",
                 to_string(pipeline_.config().model));
    return;
  }
  check_table();
  settle_table_loads();
  if (!pipeline_.table()) {
    spdlog::info(
        "waiting for the table {}: ssl-trainer writes it as soon as it has learned "
        "something (start ssl-trainer with --{} {} if it is not running)",
        table_file_.string(), options_.table_dir.empty() ? "table" : "table-dir",
        options_.table_dir.empty() ? options_.table : options_.table_dir);
  }
}

void PredictorDaemon::stop() {
  warm_up_timer_.cancel();
  if (web_) web_->stop();
  if (loader_) loader_->stop();
}

bool PredictorDaemon::serving_web() const { return web_.has_value(); }

void PredictorDaemon::when_viewer_joins(std::function<void()> handler) {
  if (web_) web_->on_viewer_joined(std::move(handler));
}

std::vector<std::pair<std::string, std::string>> PredictorDaemon::ready_facts() const {
  std::vector<std::pair<std::string, std::string>> facts{
      {"vision", options_.network.tracked() ? "tracked " + options_.network.tracker_address
                                            : options_.network.vision_address},
      {"interface", options_.network.interface},
      {"referee", options_.network.referee_address},
      {"predictions", options_.prediction_address},
      {"model", std::string(to_string(pipeline_.config().model))},
      {"table", pipeline_.needs_table() ? table_file_.string() : "none"},
      // The table predictions come from: a table the model refused is not loaded.
      {"table_loaded", pipeline_.table() ? "1" : "0"}};
  if (web_) facts.emplace_back("http", web_->url());
  return facts;
}

void PredictorDaemon::on_event(const MatchEvent& event) {
  // Between two frames, never during one: each prediction is of one table.
  if (loader_ && loader_->has_outcome()) take_table_outcomes();
  if (web_ && event.kind == MatchEventKind::vision && event.frame) {
    // Only the field view shows these.
    last_packet_s_ = clock_.steady_s();
    // Ours first, so that a prediction this packet completes shows them as of this packet.
    if (event.frame->has_detection) ours_.add(event.frame->detection);
    if (event.frame->has_geometry) stated_markings_ = event.frame->markings;
  }
  const RefereeChange change = pipeline_.handle(event);
  if (web_ && event.kind != MatchEventKind::referee) {
    if (const auto now = pipeline_.front_end().last_frame_time_s()) {
      ball_.update(pipeline_.front_end().ball().state(), *now);
    }
  }
  switch (event.kind) {
    case MatchEventKind::vision:
      if (event.frame && event.frame->has_geometry) field_log_.update(pipeline_.sampler().field());
      if (config_.infer_attacks) match_log_.update(pipeline_.front_end());
      break;
    case MatchEventKind::referee:
      if (change.any()) ours_.set_color(opposite(pipeline_.sampler().config().opponent_color));
      if (change.teams) follow_opponent_table();
      match_log_.update(pipeline_.front_end(), change);
      break;
    case MatchEventKind::tracked_vision:
      match_log_.update(pipeline_.front_end());
      break;
  }
  release_retired();
}

void PredictorDaemon::check_table() {
  if (!feed_problem_said_) {
    if (const auto problem = pipeline_.feed_problem()) {
      spdlog::warn("{}", *problem);
      feed_problem_said_ = true;
    }
  }
  if (!loader_) return;
  take_table_outcomes();
  release_retired();
  loader_->look();
}

bool PredictorDaemon::wait_for_table_loader(std::chrono::steady_clock::duration timeout) {
  return !loader_ || loader_->wait_idle(timeout);
}

bool PredictorDaemon::settle_table_loads(std::chrono::steady_clock::duration timeout) {
  const bool idle = wait_for_table_loader(timeout);
  if (loader_) take_table_outcomes();
  release_retired();
  return idle;
}

void PredictorDaemon::retire(PreparedTable old) {
  if (retired_.table || retired_.built) loader_->release(std::move(retired_));
  retired_ = std::move(old);
}

void PredictorDaemon::release_retired() {
  if (retired_.table || retired_.built) loader_->release(std::exchange(retired_, {}));
}

void PredictorDaemon::take_table_outcomes() {
  using Kind = TableLoader::Outcome::Kind;
  while (std::optional<TableLoader::Outcome> outcome = loader_->take()) {
    table_reloads_ = outcome->reloads;
    if (say_when_missing_ && outcome->first_look) {
      say_when_missing_ = false;
      if (outcome->kind != Kind::loaded) {
        spdlog::info("no table for this opponent yet: waiting for {}", outcome->path.string());
      }
    }
    switch (outcome->kind) {
      case Kind::loaded: {
        const std::shared_ptr<const StoredTable> table = outcome->prepared.table;
        const StoredTable& stored = *table;
        // The swap is all this thread does; the replaced table is freed on the loader's.
        retire(pipeline_.install_table(std::move(outcome->prepared)));
        spdlog::info(
            "loaded table {} (reload {}): {} transitions from {} formations, {} states seen",
            outcome->path.string(), outcome->reloads, stored.table.transitions(),
            stored.metadata.samples, stored.table.rows_seen());
        table_loaded_unix_ms_ = clock_.unix_ms();
        table_error_.clear();
        if (stored.metadata.step_s != config_.step_s) {
          spdlog::warn("the table was trained with --step {} but this predictor samples every {} s",
                       stored.metadata.step_s, config_.step_s);
        }
        break;
      }
      case Kind::refused:
        // A table this model cannot use (a version-1 table for --model motion): keep
        // predicting with the one we have, and say why.
        table_error_ = outcome->path.string() + ": " + outcome->error;
        spdlog::error("{}", table_error_);
        break;
      case Kind::unreadable:
        table_error_ = outcome->error;
        spdlog::error("{}; {}", outcome->error,
                      pipeline_.table() ? "keeping the table loaded before"
                                        : "still waiting for a valid table");
        break;
      case Kind::absent:
        break;
    }
  }
}

void PredictorDaemon::follow_opponent_table() {
  if (!loader_) return;
  const std::filesystem::path wanted = table_path(pipeline_.match().opponent().name);
  if (wanted == table_file_) return;
  spdlog::info("opponent '{}': predicting from {}", pipeline_.match().opponent().name,
               wanted.string());
  table_file_ = wanted;
  table_reloads_ = 0;
  loader_->follow(wanted);
  retire(pipeline_.install_table(PreparedTable{}));
  table_error_.clear();
  say_when_missing_ = true;
  loader_->look();
}

std::filesystem::path PredictorDaemon::table_path(const std::string& opponent) const {
  if (options_.table_dir.empty()) return options_.table;
  return std::filesystem::path(options_.table_dir) / team_table_file_name(opponent);
}

void PredictorDaemon::on_prediction(const PredictedFormation& predicted) {
  encode_prediction(predicted.formation(), predicted.prediction, predicted.context, datagram_);
  output_.send(std::as_bytes(std::span(datagram_.data(), datagram_.size())));
  schedule_warm_up();
  if (options_.print_predictions) {
    output_.print(
        describe_prediction(predicted.formation(), predicted.prediction, predicted.context));
  } else if (!options_.quiet) {
    // One short line a second for a person watching; the full lines are --print-predictions'.
    const double now = clock_.steady_s();
    if (!(now - last_summary_s_ < 1.0)) {
      last_summary_s_ = now;
      output_.print(
          summarize_prediction(predicted.formation(), predicted.prediction, predicted.context));
    }
  }
  // After the multicast: the view never delays the predictions.
  if (web_) {
    fill_prediction_message(predicted.formation(), predicted.prediction, predicted.context,
                            message_);
    // The ball as of the packet that completed this formation (on_event updates it only after).
    if (const auto now = pipeline_.front_end().last_frame_time_s()) {
      ball_.update(pipeline_.front_end().ball().state(), *now);
    }
    web_->broadcast(web::MessageKind::prediction,
                    web::prediction_json(message_, view_setup(), ours_.current(), ball_));
  }
}

// A feed of one frame every ~16 ms leaves the predictor asleep long enough for other work to
// push its table, histories and code out of the caches, which cost more than the prediction
// itself (bench-e2e: 3 us warm, about 38 us cold). So shortly before the next frame is due, at
// the pace of the last ones, the last prediction is run and encoded again, sending nothing.
// Faster feeds keep the caches warm by themselves and are left alone.
void PredictorDaemon::schedule_warm_up() {
  if (!(options_.warm_up_lead_ms > 0.0)) return;
  const double now = clock_.steady_s();
  if (last_prediction_s_) {
    const double gap_ms = (now - *last_prediction_s_) * 1000.0;
    // A gap of seconds (a pause in the feed) says nothing about the pace.
    if (gap_ms < 1000.0) {
      frame_period_ms_ = frame_period_ms_ ? 0.9 * *frame_period_ms_ + 0.1 * gap_ms : gap_ms;
    }
  }
  last_prediction_s_ = now;
  if (!frame_period_ms_ || *frame_period_ms_ < 3.0 * options_.warm_up_lead_ms) return;
  warm_up_timer_.expires_after(std::chrono::microseconds(
      static_cast<std::int64_t>((*frame_period_ms_ - options_.warm_up_lead_ms) * 1000.0)));
  warm_up_timer_.async_wait([this](const boost::system::error_code& error) {
    if (error) return;  // cancelled: a frame came first, or the daemon stops
    pipeline_.rehearse([this](const PredictedFormation& predicted) {
      encode_prediction(predicted.formation(), predicted.prediction, predicted.context, datagram_);
    });
    ++warm_ups_;
  });
}

}  // namespace ssl_formation::predictor
