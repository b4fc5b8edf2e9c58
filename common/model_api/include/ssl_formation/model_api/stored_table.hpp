#pragma once
// What a table file holds, as every layer passes it around: the counts on cells, what they mean
// (the metadata), and the motion model's section when the model that learned it keeps one. A
// learner hands its table over as one (Learner::stored); a forecaster predicts from one
// (Forecaster::set_table); models/table_file.hpp saves and loads it.
//
// The motion section is held by pointer to a type declared only: this interface names the
// section without depending on the model that owns it (motion_model/), and a loaded section is
// shared, never copied, by the forecasters and the pipelines that read it.

#include <cstdint>
#include <memory>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/model_api/transition_table.hpp"

namespace ssl_formation {
inline namespace motion_model {
class MotionTable;
}  // namespace motion_model
}  // namespace ssl_formation

namespace ssl_formation {
inline namespace model_api {

// What the counts mean, saved next to them.
struct TableMetadata {
  FieldSize field;
  double step_s = 2.0;
  std::uint64_t samples = 0;  // formations sampled while training
  friend bool operator==(const TableMetadata&, const TableMetadata&) = default;
};

struct StoredTable {
  TransitionTable table;
  TableMetadata metadata;
  // The motion model's rows (format version 3 to 5); none in a version-1 file, which serves only
  // the paper's model.
  std::shared_ptr<const MotionTable> motion = nullptr;
  // The format version it was read from (0 when it was not read from a file): a caller says
  // once that an older version is saved as the current one.
  std::uint32_t format_version = 0;
};

}  // namespace model_api
}  // namespace ssl_formation
