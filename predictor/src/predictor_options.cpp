// What ssl-predictor's options leave open once parsed (main.cpp parses them).

#include "ssl_formation/predictor/predictor_options.hpp"

namespace ssl_formation::predictor {

void settle_predictor_options(PredictorOptions& options) {
  app::take_table_settings(options.model, options.table);
  if (options.old_horizon_steps != app::not_given && options.horizons != "auto") {
    throw app::UsageError("give --horizons or its old spelling --horizon, not both");
  }
  const int auto_steps =
      options.old_horizon_steps != app::not_given ? options.old_horizon_steps : 2;
  options.horizon = app::horizon_steps(options.horizons, options.model.step(), auto_steps);
  if (!options.from_logs.empty()) {
    app::check_output_free({options.output, options.overwrite});
  } else if (!options.output.empty() && options.output != "-") {
    throw app::UsageError(
        "-o/--output is for --from-log; live, predictions go to "
        "--prediction-address");
  }
}

}  // namespace ssl_formation::predictor
