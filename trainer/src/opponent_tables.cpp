#include "ssl_formation/trainer/opponent_tables.hpp"

#include <spdlog/spdlog.h>

#include <stdexcept>

#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/trainer/table_store.hpp"

namespace ssl_formation::trainer {

namespace {
// The opponent's name the options give, for the first table under --table-dir.
std::string named_opponent(const MatchRules& rules) { return rules.opponent.opponent_team; }
}  // namespace

OpponentTables::OpponentTables(const TrainerOptions& options, TableSaver* saver)
    : options_(options),
      saver_(saver),
      config_(options.model.sampler_config()),
      motion_(motion_config(options)),
      rules_(match_rules(options)),
      tracked_vision_(options.network.tracked()) {
  if (per_opponent()) {
    std::error_code error;
    std::filesystem::create_directories(options_.table_dir, error);
    if (error) {
      throw std::runtime_error("--table-dir " + options_.table_dir +
                               ": cannot create it: " + error.message());
    }
    path_ =
        std::filesystem::path(options_.table_dir) / team_table_file_name(named_opponent(rules_));
  } else {
    path_ = options_.table;
  }
  training_ = open(path_);
}

std::unique_ptr<Training> OpponentTables::open(const std::filesystem::path& path) {
  const bool reset = options_.reset && !opened_.contains(path);
  opened_.insert(path);
  return open_training(path, config_, reset, motion_, rules_, tracked_vision_);
}

RefereeChange OpponentTables::handle(const MatchEvent& event) {
  const RefereeChange change = training_->handle(event);
  if (!per_opponent() || !change.teams) return change;
  const std::filesystem::path wanted = std::filesystem::path(options_.table_dir) /
                                       team_table_file_name(training_->match().opponent().name);
  if (wanted == path_) return change;
  save_if_changed();
  // The new opponent's file may be one whose save is still under way (met before in this run).
  if (saver_) saver_->wait();
  spdlog::info("opponent '{}': training {} (the table of the last one saved in {})",
               training_->match().opponent().name, wanted.string(), path_.string());
  std::unique_ptr<Training> next;
  try {
    next = open(wanted);
    saving_ = true;
  } catch (const std::runtime_error& error) {
    spdlog::error("{}; this opponent is trained into a table that is not saved", error.what());
    TrainingConfig config;
    config.sampler = config_;
    config.rules = rules_;
    config.tracked_vision = tracked_vision_;
    ResumedLearner empty = empty_table_learner(config_.grid, motion_);
    next = std::make_unique<Training>(config, empty.kind, std::move(empty.learner));
    saving_ = false;
  }
  // The new table's training knows the field the old one learned from geometry, and hears what
  // the old one heard last.
  if (training_->sampler().counters().geometry_packets > 0) {
    VisionFrame geometry;
    geometry.has_geometry = true;
    geometry.field_length = static_cast<std::int32_t>(training_->sampler().field().length_mm);
    geometry.field_width = static_cast<std::int32_t>(training_->sampler().field().width_mm);
    next->add(geometry);
  }
  next->handle(event);
  training_ = std::move(next);
  path_ = wanted;
  return change;
}

bool OpponentTables::save_if_changed() {
  if (!saving_ || !training_->changed_since_save()) return true;
  const TableBudget budget = app::table_budget_option(options_.max_table_mb);
  if (!saver_) return save_training(path_, *training_, budget).has_value();
  // A failed save is logged on the saver's thread; the next change saves again.
  saver_->submit(path_, snapshot_training(*training_), budget);
  training_->mark_saved();
  return true;
}

bool OpponentTables::save_at_exit() {
  // The saves under way first: the last one must be this one. One that failed is saved again.
  const bool saves_done = !saver_ || saver_->wait();
  if (!saving_) return true;
  if (per_opponent() && saves_done && !training_->changed_since_save()) return true;
  return save_training(path_, *training_, app::table_budget_option(options_.max_table_mb))
      .has_value();
}

}  // namespace ssl_formation::trainer
