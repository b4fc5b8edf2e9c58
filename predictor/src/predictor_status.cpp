// What ssl-predictor's daemon says of itself: its status message and line (every second, and
// at exit) and the field view's setup. The prediction loop is predictor_daemon.cpp.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <iostream>

#include "ssl_formation/base/state.hpp"
#include "ssl_formation/pipeline/prediction_message.hpp"
#include "ssl_formation/predictor/predictor_daemon.hpp"

namespace ssl_formation::predictor {

void PredictorDaemon::publish_status(const net::LiveMatchEvents* live) {
  if (!web_) return;
  const double now = clock_.steady_s();
  web::FieldViewStatus status;
  status.setup = view_setup();
  // The socket the vision comes in on: raw, or the tracker's.
  const net::ReceiverCounters* counters = !live             ? nullptr
                                          : live->tracker() ? &live->tracker()->counters()
                                                            : &live->vision().counters();
  const std::uint64_t packets =
      counters ? counters->datagrams.load() : pipeline_.sampler().counters().packets;
  status.packets = packets;
  // The rate over at least a quarter of a second: a status sent between two periodic ones (a
  // page joining) says the last rate rather than one of a few milliseconds' packets.
  if (!last_rate_s_ || now - *last_rate_s_ >= 0.25) {
    if (last_rate_s_ && now > *last_rate_s_) {
      packets_per_s_ = static_cast<double>(packets - last_rate_packets_) / (now - *last_rate_s_);
    }
    last_rate_s_ = now;
    last_rate_packets_ = packets;
  }
  status.packets_per_s = packets_per_s_;
  // The age of the last datagram on this process's own clocks: steady for the age, the wall
  // clock only to date it (never the feed's t_capture, which is the simulator's or camera's).
  const std::int64_t wall_now = clock_.unix_ms();
  status.server_unix_ms = wall_now;
  if (last_packet_s_) {
    const double age = std::max(now - *last_packet_s_, 0.0);
    status.since_packet_s = age;
    status.last_packet_unix_ms = wall_now - static_cast<std::int64_t>(age * 1000.0);
  }
  if (counters) {
    status.parse_errors = counters->parse_errors.load();
    status.kernel_drops = counters->kernel_drops.load();
  }
  status.formations = pipeline_.sampler().counters().samples;
  status.predictions = pipeline_.predictions();
  if (const auto& table = pipeline_.table()) {
    const StoredTable& stored = *table;
    status.table_loaded = true;
    status.table_transitions = stored.table.transitions();
    status.table_formations = stored.metadata.samples;
    if (stored.motion) status.table_motion_instances = stored.motion->instances();
    status.table_states_seen = stored.table.rows_seen();
  }
  status.table_reloads = table_reloads_;
  status.table_loaded_unix_ms = table_loaded_unix_ms_;
  status.table_error = table_error_;
  const web::FieldViewCounters web_counters = web_->counters();
  status.clients = web_counters.live_clients;
  status.dropped_frames = web_counters.dropped_frames;
  status.ours = ours_.current();
  status.opponent = describe(pipeline_.match().opponent(), pipeline_.sampler().attacks());
  status.game_state = std::string(to_string(pipeline_.match().game_state()));
  status.referee = describe(pipeline_.match().referee());
  status.referee_heard = pipeline_.match().referee().heard();
  status.referee_view = pipeline_.match().referee().view();
  status.phase = pipeline_.front_end().phase_now();
  status.ball = &ball_;
  const LiveScore& live_score = pipeline_.live_score();
  status.live_score = live_score.horizons();
  for (const GamePhase phase : all_game_phases) {
    // Only the phases whose predictions have been checked (not those still waiting for their
    // instant).
    const auto& horizons = live_score.horizons(phase);
    if (std::any_of(horizons.begin(), horizons.end(),
                    [](const LiveScore::Horizon& h) { return h.robots > 0.0; })) {
      status.live_score_by_phase.push_back(web::PhaseLiveScore{phase, live_score.horizons(phase)});
    }
  }
  web_->broadcast(web::MessageKind::status, web::status_json(status));
}

void PredictorDaemon::log_status(const net::LiveMatchEvents* live, app::StatusMoment moment) {
  const auto& c = pipeline_.sampler().counters();
  app::StatusLine status;
  app::add_reception(status, live, pipeline_.front_end());
  status.figure("predictions", pipeline_.predictions());
  // Why nothing is predicted, when that is why.
  if (pipeline_.needs_table() && !pipeline_.table()) status.note("no table yet");
  if (const std::string error = describe_for_status(pipeline_.live_score()); !error.empty()) {
    status.figure("live_error", error);
  }
  app::add_match(status, pipeline_.front_end());
  status.detail("formations", c.samples)
      .detail("table_reloads", table_reloads_)
      .detail("warm_ups", warm_ups_)
      .detail("referee_messages", pipeline_.match().referee().counters().messages);
  // Every prediction is sent at once: one not sent is a send that failed (and was logged).
  status.problem("send_errors",
                 pipeline_.predictions() - std::min(pipeline_.predictions(), output_.sent()));
  app::add_sampler_counters(status, c);
  app::add_reception_details(status, live, pipeline_.front_end());
  status.log("status", moment);
  // One warning per kind of bad input as it appears, so a hostile or broken feed is visible.
  for (const std::string& line : new_rejections(reported_, c)) spdlog::warn("input: {}", line);
  reported_ = c;
  if (web_) {
    const web::FieldViewCounters w = web_->counters();
    app::StatusLine view;
    if (w.live_clients == 0) view.note("no viewers");
    view.figure("viewers", w.live_clients)
        .detail("connections", w.connections)
        .problem("refused", w.refused)
        .problem("dropped_frames", w.dropped_frames)
        .problem("stalled", w.stalled_clients)
        .problem("bad_requests", w.bad_requests);
    view.log("field view", moment);
  }
}

// The hot path, from the prediction to the datagram: no allocation once warmed up, and the wire
// format written directly (see encode_prediction).

web::FieldViewSetup PredictorDaemon::view_setup() const {
  // The opponent in use: the referee's or inferred side (the configured one until then).
  const SamplerConfig& now = pipeline_.sampler().config();
  return web::FieldViewSetup{pipeline_.sampler().field(), config_.grid,
                             pipeline_.sampler().attacks().value_or(now.opponent_attacks),
                             now.opponent_color,
                             web::markings_for(pipeline_.sampler().field(), stated_markings_)};
}

}  // namespace ssl_formation::predictor
