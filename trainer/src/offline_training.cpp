// ssl-trainer --from-log: official log files through the same Training the live mode runs, then
// one atomic save. Everything read before a damaged part of a file is kept.

#include <spdlog/spdlog.h>

#include <optional>

#include "ssl_formation/app/progress.hpp"
#include "ssl_formation/log_file.hpp"
#include "ssl_formation/trainer/table_store.hpp"
#include "ssl_formation/trainer/trainer.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::trainer {

namespace {
// Logs above this size get a progress bar.
constexpr std::uint64_t progress_bar_bytes = 4 << 20;
}  // namespace

int run_offline(const TrainerOptions& options) {
  const SamplerConfig config = options.model.sampler_config();
  const std::filesystem::path table_path = options.table;
  std::unique_ptr<Training> training =
      open_training(table_path, config, options.reset, motion_config(options), match_rules(options));
  bool every_file_whole = true;
  VisionFrame frame;  // detection packets decoded straight from the log's bytes
  for (const std::string& file : options.from_logs) {
    Result<LogReader> reader = LogReader::open(file);
    if (!reader) {
      spdlog::error("{}", reader.error().message);
      every_file_whole = false;
      continue;
    }
    training->start_new_stream();
    const std::uint64_t transitions_before = training->table().transitions();
    const std::uint64_t samples_before = training->samples();
    std::optional<app::ProgressBar> bar;
    if (reader->compressed_size() > progress_bar_bytes)
      bar.emplace("training from " + file, reader->compressed_size());
    std::uint64_t frames = 0;
    std::uint64_t outside_play_before = training->samples_outside_play();
    LogReader::MatchInput kind{};
    std::string_view referee;
    std::int64_t receive_ns = 0;
    while (reader->next_match_input(kind, frame, referee, &receive_ns)) {
      if (kind == LogReader::MatchInput::referee) {
        training->add_referee(referee, static_cast<double>(receive_ns) * 1e-9);
        continue;
      }
      training->add(frame);
      if ((++frames & 4095) == 0 && bar) bar->update(reader->compressed_offset(), frames);
    }
    if (bar) bar->finish(frames);
    const LogReadCounters& c = reader->counters();
    spdlog::info(
        "{}: {} vision packets ({} parse errors), {} referee, skipped {} tracker, {} other; "
        "{} formations, {} transitions",
        file, frames, c.parse_errors, c.referee, c.tracker, c.unknown + c.blank + c.legacy_unusable,
        training->samples() - samples_before, training->table().transitions() - transitions_before);
    if (training->match().referee().heard()) {
      spdlog::info("{}: opponent {}; {} formations outside running play not learned (--learn-during "
                   "{}); last {}",
                   file, describe(training->match().opponent(), training->sampler().attacks()),
                   training->samples_outside_play() - outside_play_before,
                   to_string(training->learn_during()), describe(training->match().referee()));
    }
    switch (reader->ending()) {
      case LogReader::Ending::none:
        break;
      case LogReader::Ending::cut_off:
        // What a recorder killed mid-write leaves: only the last message is lost.
        if (options.strict) {
          spdlog::error("{}; the {} vision packets before it were used (--strict)", reader->error(),
                        frames);
          every_file_whole = false;
        } else {
          spdlog::warn(
              "{}: the file ends inside its last message; the {} vision packets before "
              "it were used",
              reader->error(), frames);
        }
        break;
      case LogReader::Ending::damaged:
        spdlog::error("{}; the {} vision packets before it were used", reader->error(), frames);
        every_file_whole = false;
        break;
    }
  }
  if (!save_training(table_path, *training)) return 1;
  spdlog::info("saved {}: {} transitions from {} formations, {} states seen", table_path.string(),
               training->table().transitions(), training->samples(), training->table().rows_seen());
  if (const auto& motion = training->motion()) {
    spdlog::info("saved {}: motion model, {} horizons: motion_instances={} motion_held_out={} "
                 "motion_rows={}",
                 table_path.string(), motion->config().horizons, motion->instances(),
                 motion->held_out(), motion->rows());
  }
  return every_file_whole ? 0 : 1;
}

}  // namespace ssl_formation::trainer
