// ssl-predictor --from-log: official log files through the same PredictionPipeline the daemon
// runs, as fast as the machine allows, every prediction written as CSV (prediction_csv.hpp).
// What the daemon would have multicast during the recorded match, without any network.

#include <spdlog/spdlog.h>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "ssl_formation/app/progress.hpp"
#include "ssl_formation/files/log_events.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/files/replacing_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/pipeline/prediction_csv.hpp"
#include "ssl_formation/predictor/predictor_options.hpp"

namespace ssl_formation::predictor {

namespace {
// Logs above this size get a progress bar; CSV text is handed to the stream in blocks this big.
constexpr std::uint64_t progress_bar_bytes = 4 << 20;
constexpr std::size_t flush_bytes = 1 << 20;
}  // namespace

int run_from_log(const PredictorOptions& options) {
  if (!options.table_dir.empty()) {
    throw app::UsageError("--from-log predicts from one table: give --table, not --table-dir");
  }
  const PredictionConfig config = prediction_config(options);
  std::shared_ptr<const StoredTable> table;
  if (describe(config.model).keeps_table) {
    auto loaded = load_table(options.table, config.sampler.grid);
    if (!loaded) throw std::runtime_error(loaded.error().message);
    if (loaded->metadata.step_s != config.sampler.step_s) {
      spdlog::warn("the table was trained with --step {} but the logs are sampled every {} s",
                   loaded->metadata.step_s, config.sampler.step_s);
    }
    table = std::make_shared<const StoredTable>(std::move(*loaded));
  }

  const bool to_stdout = options.output.empty() || options.output == "-";
  // Replaced only when every log was read whole: a failed run leaves an earlier file as it was.
  std::optional<ReplacingFile> file;
  if (!to_stdout) file.emplace(options.output, true);
  std::ostream& out = to_stdout ? std::cout : file->stream();
  std::string text(prediction_csv_header());
  const auto flush = [&] {
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    text.clear();
  };

  PredictionPipeline pipeline(config, [&](const PredictedFormation& predicted) {
    append_prediction_csv(predicted, text);
    if (text.size() >= flush_bytes) flush();
  });
  try {
    if (table) pipeline.set_table(table);
  } catch (const std::invalid_argument& error) {
    throw std::runtime_error(options.table + ": " + error.what());
  }

  bool every_file_whole = true;
  for (const std::string& path : options.from_logs) {
    Result<LogReader> reader = LogReader::open(path);
    if (!reader) {
      spdlog::error("{}", reader.error().message);
      every_file_whole = false;
      continue;
    }
    // Each file is its own stream: no prediction follows a formation of another file.
    pipeline.start_new_stream();
    const std::uint64_t predictions_before = pipeline.predictions();
    std::optional<app::ProgressBar> bar;
    if (reader->compressed_size() > progress_bar_bytes && !to_stdout)
      bar.emplace("predicting from " + path, reader->compressed_size());
    const std::uint64_t frames = replay_log(*reader, pipeline, [&](std::uint64_t vision) {
      if (bar) bar->update(reader->compressed_offset(), vision);
    });
    if (bar) bar->finish(frames);
    spdlog::info("{}: {} vision packets ({} parse errors), {} predictions", path, frames,
                 reader->counters().parse_errors, pipeline.predictions() - predictions_before);
    if (reader->ending() == LogReader::Ending::damaged) {
      spdlog::error("{}; the {} vision packets before it were used", reader->error(), frames);
      every_file_whole = false;
    } else if (reader->ending() == LogReader::Ending::cut_off) {
      spdlog::warn(
          "{}: the file ends inside its last message; the {} vision packets before it "
          "were used",
          reader->error(), frames);
    }
  }
  if (const auto problem = pipeline.feed_problem()) spdlog::warn("{}", *problem);
  flush();
  out.flush();
  if (!out)
    throw std::runtime_error("cannot write " + (to_stdout ? "standard output" : options.output));
  if (file && !every_file_whole) {
    file->discard();
    spdlog::error("{} not written (left as it was): not every log could be read whole",
                  options.output);
    return 1;
  }
  if (file) file->commit();
  spdlog::info("{} predictions from {} formations{}", pipeline.predictions(),
               pipeline.sampler().counters().samples,
               to_stdout ? std::string() : " written to " + options.output);
  return every_file_whole ? 0 : 1;
}

}  // namespace ssl_formation::predictor
