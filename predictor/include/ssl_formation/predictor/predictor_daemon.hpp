#pragma once
// ssl-predictor's daemon as an object: the match's events in (from the network in the program,
// from a test's hands in-process), each prediction out to a PredictionOutput, the table followed
// as the trainer replaces it, and the live field view (--http-port). It reads time only from the
// clock it is given, so a test drives it with a clock of its own and no sockets; run_daemon()
// wires it to the network, the timers and the signals.

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ssl_formation/app/clock.hpp"
#include "ssl_formation/app/daemon.hpp"
#include "ssl_formation/match/match_event.hpp"
#include "ssl_formation/net/live_match_events.hpp"
#include "ssl_formation/net/multicast.hpp"
#include "ssl_formation/pipeline/prediction_pipeline.hpp"
#include "ssl_formation/predictor/predictor_options.hpp"
#include "ssl_formation/predictor/table_loader.hpp"
#include "ssl_formation/predictor/table_watcher.hpp"
// The field view's library (predictor/web).
#include "field_view_json.hpp"
#include "field_view_server.hpp"
#include "team_robots.hpp"

namespace ssl_formation::predictor {

// Where the predictions go: the multicast group and standard output in the program, memory in
// tests.
class PredictionOutput {
 public:
  virtual ~PredictionOutput() = default;
  // One FormationPrediction, encoded.
  virtual void send(std::span<const std::byte> datagram) = 0;
  // Its readable line (not called with --quiet).
  virtual void print(std::string_view line) = 0;
  virtual std::uint64_t sent() const = 0;
};

// The program's: --prediction-address from --prediction-interface, and standard output.
class MulticastPredictionOutput final : public PredictionOutput {
 public:
  MulticastPredictionOutput(boost::asio::io_context& io, const PredictorOptions& options);
  void open() { sender_.open(); }
  void send(std::span<const std::byte> datagram) override { sender_.send(datagram); }
  void print(std::string_view line) override;
  std::uint64_t sent() const override { return sender_.sent(); }

 private:
  net::MulticastSender sender_;
};

class PredictorDaemon final : public MatchEventSink {
 public:
  // Throws app::UsageError for bad options (a --table in a folder that does not exist among
  // them). `io` runs the field view and the warm-up timer; a test that drives the daemon by hand
  // need not run it. `load_file` reads the table files (load_table when empty; a test's can take
  // its time).
  PredictorDaemon(boost::asio::io_context& io, const PredictorOptions& options,
                  const PredictionConfig& config, const app::Clock& clock, PredictionOutput& output,
                  TableFileLoader load_file = {});
  PredictorDaemon(const PredictorDaemon&) = delete;
  PredictorDaemon& operator=(const PredictorDaemon&) = delete;

  // Starts the field view (a busy port fails here) and loads the table there at start, waiting
  // for it: nothing is predicted before.
  void start();
  // Stops the field view and the warm-up, and joins the table's loader thread: after the file
  // read under way, if any (see TableLoader::stop).
  void stop();

  void on_event(const MatchEvent& event) override;
  void start_new_stream() override { pipeline_.start_new_stream(); }

  // What the reload timer does: installs a table the loader has ready, asks it to look at the
  // file again (it reads and prepares a replaced one on its own thread), and says once, in plain
  // words, when the model cannot predict from this feed. Never waits for the file. A table the
  // loader has ready is also installed before the next frame is handled.
  void check_table();
  // Waits until the loader has nothing under way (false if `timeout` passed first). What it
  // has ready is installed before the next frame, or by check_table().
  bool wait_for_table_loader(
      std::chrono::steady_clock::duration timeout = std::chrono::steady_clock::duration::max());
  // The same, then installs what the loader has ready: start() does, for the table there at
  // start, and tests.
  bool settle_table_loads(
      std::chrono::steady_clock::duration timeout = std::chrono::steady_clock::duration::max());
  // One status line, then a warning for each kind of bad input that arrived since the last one.
  // `live`: the network's counters, when the events come from there. At stop, whatever did not fit
  // on the line follows it.
  void log_status(const net::LiveMatchEvents* live = nullptr,
                  app::StatusMoment moment = app::StatusMoment::periodic);
  // The field view's status message.
  void publish_status(const net::LiveMatchEvents* live = nullptr);

  bool serving_web() const;
  // Runs `handler` when a field view page connects (after it is counted among the viewers).
  void when_viewer_joins(std::function<void()> handler);
  // What the ready file says once the sockets are joined and the table there at start loaded.
  std::vector<std::pair<std::string, std::string>> ready_facts() const;

  const PredictionPipeline& pipeline() const { return pipeline_; }
  // The table file followed (the current opponent's with --table-dir).
  const std::filesystem::path& table_file() const { return table_file_; }
  // Tables loaded from it and put in use or refused (TableWatcher::reloads).
  std::uint64_t table_reloads() const { return table_reloads_; }
  const std::string& table_error() const { return table_error_; }
  std::uint64_t warm_ups() const { return warm_ups_; }

 private:
  // The hot path, from the prediction to the datagram.
  void on_prediction(const PredictedFormation& predicted);
  // Rehearses the last prediction shortly before the next frame is due (see the .cpp).
  void schedule_warm_up();
  // --table-dir: the current opponent's table, loaded as soon as the referee names another.
  void follow_opponent_table();
  // Puts what the loader has to say in use: a table, or why there is none.
  void take_table_outcomes();
  // A table the pipeline replaced, kept until the frame that replaced it is predicted and sent,
  // then freed on the loader's thread: freeing a large model there (munmap, page-table
  // shootdowns) then overlaps the wait for the next frame, not this one's prediction.
  void retire(PreparedTable old);
  void release_retired();
  std::filesystem::path table_path(const std::string& opponent) const;
  web::FieldViewSetup view_setup() const;

  const PredictorOptions& options_;
  const app::Clock& clock_;
  PredictionOutput& output_;
  SamplerConfig config_;
  PredictionPipeline pipeline_;
  std::filesystem::path table_file_;
  std::uint64_t table_reloads_ = 0;
  // follow_opponent_table's: say so if the new opponent has no table yet.
  bool say_when_missing_ = false;
  std::string datagram_;                // FormationPrediction datagrams, by encode_prediction
  proto::FormationPrediction message_;  // for the field view only
  SamplerCounters reported_;            // counters at the last status line
  app::FieldSizeLog field_log_;
  app::MatchLog match_log_;
  bool feed_problem_said_ = false;
  std::string table_error_;
  // The field view (--http-port), and what only it needs.
  web::TeamRobots ours_;
  web::BallTrail ball_;
  std::optional<FieldMarkings> stated_markings_;  // the last geometry packet's
  std::optional<web::FieldViewServer> web_;
  std::optional<double> last_packet_s_;  // on the clock
  double last_summary_s_ = -1e300;       // when the last once-a-second summary line was printed
  std::optional<double> last_rate_s_;
  std::uint64_t last_rate_packets_ = 0;
  double packets_per_s_ = 0.0;
  std::optional<std::int64_t> table_loaded_unix_ms_;
  // The warm-up before each expected frame (schedule_warm_up).
  boost::asio::steady_timer warm_up_timer_;
  std::optional<double> last_prediction_s_;
  std::optional<double> frame_period_ms_;
  std::uint64_t warm_ups_ = 0;
  PreparedTable retired_;  // see retire()
  // Reads and prepares the table off the prediction's thread (models that keep a table only).
  // Last, so that its thread, which prepares with pipeline_, stops before anything else goes.
  std::optional<TableLoader> loader_;
};

}  // namespace ssl_formation::predictor
