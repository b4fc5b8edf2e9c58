// ssl-trainer with the motion model: --model motion (the default) trains and saves a version-3
// table and resumes only one, --model paper stays on version 1, --horizon, merging version-3
// tables, and the refusals of a table of the other model. Run in-process through the trainer
// library: the options as ssl-trainer parses them, then run_offline or merge_tables.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "circling_robots.hpp"
#include "motion_table_sums.hpp"
#include "scratch_dir.hpp"
#include "ssl_formation/files/log_file.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/trainer/table_store.hpp"
#include "ssl_formation/trainer/trainer.hpp"
#include "ssl_formation/vision/vision_packet.hpp"
#include "ssl_vision_wrapper.pb.h"

namespace ssl_formation::trainer {
namespace {

namespace fs = std::filesystem;
using ssl_formation::testing::as_saved;
using ssl_formation::testing::same_coarse_evidence;

class TempDir : public testing::ScratchDir {
 public:
  TempDir() : ScratchDir("sslf-motion-training") {}
};

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::uint32_t version_of(const fs::path& path) {
  const std::string bytes = read_bytes(path);
  if (bytes.size() < 12) return 0;
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i)
    value |= std::uint32_t{static_cast<std::uint8_t>(bytes[8 + i])} << (8 * i);
  return value;
}

using Entries = std::vector<std::tuple<StateIndex, StateIndex, TransitionTable::Count>>;
Entries entries(const TransitionTable& table) {
  Entries out;
  table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count count) {
    out.emplace_back(from, to, count);
  });
  return out;
}

StoredTable load(const fs::path& path) {
  auto loaded = load_table(path);
  if (!loaded) throw std::runtime_error(loaded.error().message);
  return std::move(*loaded);
}

using ssl_formation::testing::circling_stream;

void write_log(const fs::path& path, const std::vector<SSL_WrapperPacket>& packets) {
  auto writer = LogWriter::create(path);
  ASSERT_TRUE(writer) << writer.error().message;
  for (const auto& packet : packets) {
    const auto t_ns = static_cast<std::int64_t>(packet.detection().t_capture() * 1e9);
    ASSERT_TRUE(writer->write_vision(packet, t_ns)) << writer->error();
  }
  ASSERT_TRUE(writer->close());
}

// ssl-trainer's command line, parsed as main() parses it.
TrainerOptions parse(std::vector<std::string> args) {
  args.insert(args.begin(), "ssl-trainer");
  std::vector<const char*> argv;
  for (const auto& arg : args) argv.push_back(arg.c_str());
  TrainerOptions options;
  if (!parse_trainer_options(static_cast<int>(argv.size()), argv.data(), options)) {
    throw std::runtime_error("--help");
  }
  settle_trainer_options(options);  // as main does
  return options;
}

// `ssl-trainer ARGS`, --from-log mode, in-process: the exit status.
int train_from_logs(const std::vector<std::string>& args) { return run_offline(parse(args)); }

// What Training computes from the same streams with the options' model, one stream per file.
std::unique_ptr<Training> library_training(
    const TrainerOptions& options, const std::vector<std::vector<SSL_WrapperPacket>>& streams) {
  const auto motion = motion_config(options);
  auto training = std::make_unique<Training>(
      options.model.sampler_config(), TransitionTable(options.model.parsed_grid()), 0,
      motion ? std::optional<MotionTable>(MotionTable(*motion)) : std::nullopt);
  for (const auto& stream : streams) {
    training->start_new_stream();
    for (const auto& packet : stream) training->add(packet);
  }
  return training;
}

class MotionTraining : public ::testing::Test {
 protected:
  void SetUp() override {
    a_ = circling_stream(10.0, 20.0, 1);
    b_ = circling_stream(200.0, 25.0, 2);
    write_log(dir_.path() / "a.log", a_);
    write_log(dir_.path() / "b.log.gz", b_);
  }
  fs::path at(const std::string& name) const { return dir_.path() / name; }

  TempDir dir_;
  std::vector<SSL_WrapperPacket> a_;
  std::vector<SSL_WrapperPacket> b_;
};

TEST_F(MotionTraining, FromLogWritesAMotionTableByDefault) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("t.bin").string()}),
            0);
  EXPECT_EQ(version_of(at("t.bin")), table_file_compact_motion_version);
  const StoredTable stored = load(at("t.bin"));
  ASSERT_TRUE(stored.motion != nullptr);
  EXPECT_EQ(stored.motion->config().horizons, 3) << "--horizon defaults to 3";
  EXPECT_EQ(stored.motion->config().step_s, 0.5) << "--step auto is 0.5 s for the motion model";
  EXPECT_GT(stored.motion->instances(), 0u);

  const auto expected = library_training(parse({}), {a_});
  EXPECT_TRUE(*stored.motion == as_saved(*expected->stored_table().motion));
  EXPECT_EQ(entries(stored.table), entries(expected->stored_table().table));
  EXPECT_EQ(stored.metadata.samples, expected->samples());
}

TEST_F(MotionTraining, ModelPaperWritesTheVersionOneTableOfBefore) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("t.bin").string(),
                             "--model", "paper"}),
            0);
  EXPECT_EQ(version_of(at("t.bin")), table_file_version);
  const StoredTable stored = load(at("t.bin"));
  EXPECT_FALSE(stored.motion != nullptr);

  // The bytes the paper's training saves: step sampling, counts only.
  const TrainerOptions paper = parse({"--model", "paper"});
  EXPECT_EQ(paper.model.sampler_config().sampling, Sampling::step);
  const auto expected = library_training(paper, {a_});
  ASSERT_GT(expected->stored_table().table.transitions(), 0u);
  ASSERT_TRUE(save_training(at("expected.bin"), *expected));
  EXPECT_EQ(read_bytes(at("t.bin")), read_bytes(at("expected.bin")));
}

TEST_F(MotionTraining, HorizonOption) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("t.bin").string(),
                             "--horizon", "5", "--step", "1"}),
            0);
  const StoredTable stored = load(at("t.bin"));
  ASSERT_TRUE(stored.motion != nullptr);
  EXPECT_EQ(stored.motion->config().horizons, 5);
  EXPECT_EQ(stored.motion->config().step_s, 1.0);
  const auto expected = library_training(parse({"--horizon", "5", "--step", "1"}), {a_});
  EXPECT_TRUE(*stored.motion == as_saved(*expected->stored_table().motion));

  EXPECT_THROW((void)motion_config(parse({"--horizon", "0"})), app::UsageError);
  EXPECT_THROW((void)motion_config(parse({"--horizon", "17"})), app::UsageError);
  EXPECT_NO_THROW((void)motion_config(parse({"--horizon", "16"})));
  EXPECT_FALSE(motion_config(parse({"--model", "paper", "--horizon", "0"})).has_value())
      << "--horizon means nothing to the paper's model";
  EXPECT_THROW((void)motion_config(parse({"--model", "markov"})), app::UsageError);
  // A baseline keeps no table: nothing to train.
  EXPECT_THROW((void)motion_config(parse({"--model", "persistence"})), app::UsageError);
}

// Resumed, a saved table goes on adding: what it folded stays at its parents' keys, and every
// level a pruning keeps exactly holds what training on both logs at once holds.
TEST_F(MotionTraining, ResumesASavedTableAndGoesOn) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("t.bin").string()}),
            0);
  ASSERT_EQ(
      train_from_logs({"--from-log", at("b.log.gz").string(), "--table", at("t.bin").string()}), 0);
  const StoredTable stored = load(at("t.bin"));
  ASSERT_TRUE(stored.motion != nullptr);
  const auto expected = library_training(parse({}), {a_, b_});
  EXPECT_TRUE(same_coarse_evidence(*stored.motion, *expected->stored_table().motion));
  EXPECT_EQ(entries(stored.table), entries(expected->stored_table().table));
  EXPECT_EQ(stored.metadata.samples, expected->samples());
}

// The refusal names the file and what to do, and leaves the file byte for byte as it was.
void expect_refused(const fs::path& path, const TrainerOptions& options,
                    const std::vector<std::string>& in_message) {
  const std::string before = read_bytes(path);
  try {
    (void)open_training(path, options.model.sampler_config(), false, motion_config(options));
    ADD_FAILURE() << "open_training accepted " << path;
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    for (const std::string& part : in_message) {
      EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' in: " << message;
    }
  }
  EXPECT_EQ(read_bytes(path), before) << "a refused file must be left as it was";
}

TEST_F(MotionTraining, RefusesToResumeAVersionOneTableWithTheMotionModel) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("t.bin").string(),
                             "--model", "paper"}),
            0);
  expect_refused(at("t.bin"), parse({}), {"only the paper's counts", "--model paper", "--table"});
  // run_offline refuses it the same way, before reading any log.
  EXPECT_THROW(train_from_logs({"--from-log", at("b.log.gz").string(), "--table",
                                at("t.bin").string(), "--model", "motion"}),
               std::runtime_error);
  EXPECT_EQ(version_of(at("t.bin")), table_file_version);
  // --reset replaces it at the first save.
  auto training =
      open_training(at("t.bin"), parse({}).model.sampler_config(), true, motion_config(parse({})));
  EXPECT_TRUE(training->stored_table().motion != nullptr);
}

TEST_F(MotionTraining, RefusesToResumeAVersionTwoTableWithThePaperModel) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("t.bin").string()}),
            0);
  expect_refused(at("t.bin"), parse({"--model", "paper"}), {"motion model", "--model motion"});
}

TEST_F(MotionTraining, RefusesToResumeAnotherHorizon) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("t.bin").string()}),
            0);
  expect_refused(at("t.bin"), parse({"--horizon", "4"}),
                 {"--horizons 1.5 (3 steps), not 2", "--reset"});
}

TEST_F(MotionTraining, SavesAndResumesInProcess) {
  const TrainerOptions options = parse({"--horizon", "2"});
  auto training =
      open_training(at("t.bin"), options.model.sampler_config(), false, motion_config(options));
  ASSERT_TRUE(training->stored_table().motion != nullptr);
  for (const auto& packet : a_) training->add(packet);
  ASSERT_TRUE(training->changed_since_save());
  ASSERT_TRUE(save_training(at("t.bin"), *training));
  EXPECT_FALSE(training->changed_since_save());
  EXPECT_EQ(version_of(at("t.bin")), table_file_compact_motion_version);

  auto resumed =
      open_training(at("t.bin"), options.model.sampler_config(), false, motion_config(options));
  ASSERT_TRUE(resumed->stored_table().motion != nullptr);
  EXPECT_TRUE(*resumed->stored_table().motion == as_saved(*training->stored_table().motion));
  EXPECT_EQ(entries(resumed->stored_table().table), entries(training->stored_table().table));
  EXPECT_FALSE(resumed->changed_since_save());
}

// Training on a log's VisionFrames (LogReader::next_vision decoding detection packets straight
// from the bytes) gives the tables of training on its parsed packets, the motion table bit for
// bit: on the circling robots and on a grSim recording (geometry inside some of its packets).
TEST_F(MotionTraining, FramesReadFromALogTrainWhatItsPacketsTrain) {
  const TrainerOptions options = parse({});
  const fs::path grsim = fs::path(SSLF_TEST_DATA_DIR) / "grsim-4cam-11v11-idle.log.gz";
  std::vector<std::vector<SSL_WrapperPacket>> streams;
  const auto motion = motion_config(options);
  Training from_frames(options.model.sampler_config(), TransitionTable(options.model.parsed_grid()),
                       0, MotionTable(*motion));
  for (const fs::path& file : {at("a.log"), at("b.log.gz"), grsim}) {
    auto packets = LogReader::open(file);
    auto frames = LogReader::open(file);
    ASSERT_TRUE(packets && frames) << file;
    streams.emplace_back();
    SSL_WrapperPacket packet;
    while (packets->next_vision(packet)) streams.back().push_back(packet);
    from_frames.start_new_stream();
    VisionFrame frame;
    while (frames->next_vision(frame)) from_frames.add(frame);
  }
  ASSERT_EQ(streams[0].size(), a_.size());
  const auto from_packets = library_training(options, streams);
  ASSERT_TRUE(from_frames.stored_table().motion != nullptr);
  EXPECT_GT(from_frames.stored_table().motion->instances(), 0u);
  EXPECT_TRUE(*from_frames.stored_table().motion == *from_packets->stored_table().motion);
  EXPECT_EQ(entries(from_frames.stored_table().table), entries(from_packets->stored_table().table));
  EXPECT_EQ(from_frames.samples(), from_packets->samples());
}

// A learner whose table outgrows ModelSettings::motion_rows_in_memory prunes it as a saved table
// is pruned: it holds fewer rows than one that keeps them all, and the same evidence at
// every level a pruning keeps exactly.
TEST_F(MotionTraining, ALearnerBoundedInMemoryKeepsTheEvidenceOfOneThatIsNot) {
  const TrainerOptions options = parse({});
  const auto learn = [&](std::size_t rows_in_memory) {
    ModelSettings settings;
    settings.grid = options.model.parsed_grid();
    settings.step_s = options.model.sampler_config().step_s;
    settings.horizons = motion_config(options)->horizons;
    settings.motion_rows_in_memory = rows_in_memory;
    TrainingConfig config;
    config.sampler = options.model.sampler_config();
    auto training = std::make_unique<Training>(config, ModelKind::motion,
                                               make_learner(ModelKind::motion, settings));
    for (const auto* stream : {&a_, &b_}) {
      training->start_new_stream();
      for (const auto& packet : *stream) training->add(packet);
    }
    return training;
  };
  const auto unbounded = learn(0);
  const StoredTable unbounded_table = unbounded->stored_table();
  const MotionTable& all_rows = *unbounded_table.motion;
  const std::size_t saved_rows = as_saved(all_rows).rows();
  ASSERT_LT(4 * saved_rows, 3 * all_rows.rows()) << "the logs must give rows a pruning folds";

  const std::size_t bound = all_rows.rows() / 4;
  const auto bounded = learn(bound);
  const StoredTable bounded_table = bounded->stored_table();
  const MotionTable& held = *bounded_table.motion;
  EXPECT_LT(held.rows(), all_rows.rows() / 2)
      << "pruned " << held.rows() << " of " << all_rows.rows();
  EXPECT_TRUE(same_coarse_evidence(held, all_rows));
  EXPECT_EQ(held.instances(), all_rows.instances());
  EXPECT_EQ(entries(bounded_table.table), entries(unbounded_table.table));
}

// Two tables trained from two logs and merged hold what the table trained on both logs at once
// holds, at every level a pruning keeps exactly.
TEST_F(MotionTraining, MergeOfMotionTablesEqualsTrainingOnBothLogs) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("ta.bin").string()}),
            0);
  ASSERT_EQ(
      train_from_logs({"--from-log", at("b.log.gz").string(), "--table", at("tb.bin").string()}),
      0);
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), at("b.log.gz").string(), "--table",
                             at("tab.bin").string()}),
            0);
  merge_tables({at("ta.bin").string(), at("tb.bin").string()}, at("merged.bin"));
  EXPECT_EQ(version_of(at("merged.bin")), table_file_compact_motion_version);

  const StoredTable merged = load(at("merged.bin"));
  const StoredTable together = load(at("tab.bin"));
  ASSERT_TRUE(merged.motion && together.motion);
  EXPECT_TRUE(same_coarse_evidence(*merged.motion, *together.motion));
  EXPECT_EQ(merged.motion->held_out(), together.motion->held_out());
  EXPECT_GT(merged.motion->held_out(), 0u);
  EXPECT_EQ(entries(merged.table), entries(together.table));
  EXPECT_EQ(merged.metadata.samples, together.metadata.samples);
  const auto expected = library_training(parse({}), {a_, b_});
  EXPECT_TRUE(same_coarse_evidence(*merged.motion, *expected->stored_table().motion));
}

TEST_F(MotionTraining, MergeOfVersionOneTablesStaysVersionOne) {
  for (const auto& [log, table] : {std::pair{"a.log", "ta.bin"}, std::pair{"b.log.gz", "tb.bin"}}) {
    ASSERT_EQ(train_from_logs({"--from-log", at(log).string(), "--table", at(table).string(),
                               "--model", "paper"}),
              0);
  }
  merge_tables({at("ta.bin").string(), at("tb.bin").string()}, at("merged.bin"));
  EXPECT_EQ(version_of(at("merged.bin")), table_file_version);
  EXPECT_FALSE(load(at("merged.bin")).motion != nullptr);
}

TEST_F(MotionTraining, MergeRefusesToMixTheModels) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("v2.bin").string()}),
            0);
  ASSERT_EQ(train_from_logs({"--from-log", at("b.log.gz").string(), "--table",
                             at("v1.bin").string(), "--model", "paper"}),
            0);
  for (const auto& inputs :
       {std::vector<std::string>{at("v2.bin").string(), at("v1.bin").string()},
        std::vector<std::string>{at("v1.bin").string(), at("v2.bin").string()}}) {
    try {
      merge_tables(inputs, at("merged.bin"));
      ADD_FAILURE() << "merged a version-1 and a version-3 table";
    } catch (const std::runtime_error& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(at("v1.bin").string()), std::string::npos) << message;
      EXPECT_NE(message.find(at("v2.bin").string()), std::string::npos) << message;
      EXPECT_NE(message.find("version-1"), std::string::npos) << message;
      EXPECT_NE(message.find("version-5"), std::string::npos) << message;
    }
    EXPECT_FALSE(fs::exists(at("merged.bin")));
  }
}

TEST_F(MotionTraining, MergeRefusesOtherHorizons) {
  ASSERT_EQ(train_from_logs({"--from-log", at("a.log").string(), "--table", at("t3.bin").string()}),
            0);
  ASSERT_EQ(train_from_logs({"--from-log", at("b.log.gz").string(), "--table",
                             at("t4.bin").string(), "--horizon", "4"}),
            0);
  try {
    merge_tables({at("t3.bin").string(), at("t4.bin").string()}, at("merged.bin"));
    ADD_FAILURE() << "merged tables of other horizons";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("--horizon"), std::string::npos) << error.what();
  }
  EXPECT_FALSE(fs::exists(at("merged.bin")));
}

}  // namespace
}  // namespace ssl_formation::trainer
