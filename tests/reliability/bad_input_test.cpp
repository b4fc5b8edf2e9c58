// Hostile input against the running daemons (issue 6, part 2): a seeded clean stream with bad
// datagrams of every kind interleaved. The daemons stay up, count each kind (status lines and one
// warning per kind), and their table and predictions equal those of the clean stream alone.

#include <signal.h>

#include <array>
#include <functional>
#include <iostream>
#include <limits>
#include <numeric>
#include <random>

#include "reliability_support.hpp"
#include "ssl_formation/paper_model/predictor.hpp"
#include "ssl_formation/vision/vision_packet.hpp"

namespace ssl_formation::reliability {
namespace {

using testing::ChildProcess;
using testing::TempDir;

enum class Bad {
  random_bytes,
  truncated,
  nan_coordinates,
  inf_coordinates,
  huge_coordinates,
  thousand_robots,
  camera_4e9,
  zero_field,
  negative_field,
  late_frame,       // the frame before the last one again: out of order
  old_frame,        // a frame five formations old: another clock's, set aside
  duplicate_frame,  // the last frame again
  other_message,    // a FormationPrediction sent to the vision port
  count
};
constexpr const char* bad_names[] = {
    "random bytes",        "truncated",   "NaN coordinates", "inf coordinates",
    "1e30 coordinates",    "1000 robots", "camera id 4e9",   "zero field size",
    "negative field size", "late frame",  "old frame",       "duplicate frame",
    "FormationPrediction"};

struct DirtyStream {
  std::vector<std::string> datagrams;        // what goes on the wire, in order
  std::vector<SSL_WrapperPacket> decodable;  // those that decode, in order (what a daemon sees)
  std::size_t parse_errors = 0;
  std::array<std::size_t, static_cast<int>(Bad::count)> sent{};
  std::size_t duplicate_id_packets = 0;
};

void with_robots(SSL_WrapperPacket& packet,
                 const std::function<void(SSL_DetectionRobot&)>& change) {
  for (auto& robot : *packet.mutable_detection()->mutable_robots_yellow()) change(robot);
}

std::string bad_datagram(Bad kind, std::mt19937_64& random,
                         const std::vector<SSL_WrapperPacket>& detections) {
  const SSL_WrapperPacket& last = detections.back();
  SSL_WrapperPacket packet = last;
  switch (kind) {
    case Bad::random_bytes: {
      std::string bytes(std::uniform_int_distribution<int>(1, 1400)(random), '\0');
      for (char& c : bytes) c = static_cast<char>(random());
      return bytes;
    }
    case Bad::truncated: {
      const std::string whole = last.SerializeAsString();
      return whole.substr(0,
                          std::uniform_int_distribution<std::size_t>(1, whole.size() - 1)(random));
    }
    case Bad::nan_coordinates:
      with_robots(packet,
                  [](SSL_DetectionRobot& r) { r.set_x(std::numeric_limits<float>::quiet_NaN()); });
      break;
    case Bad::inf_coordinates:
      with_robots(packet,
                  [](SSL_DetectionRobot& r) { r.set_y(-std::numeric_limits<float>::infinity()); });
      break;
    case Bad::huge_coordinates:
      with_robots(packet, [](SSL_DetectionRobot& r) { r.set_x(1e30F); });
      break;
    case Bad::thousand_robots: {
      auto* robots = packet.mutable_detection()->mutable_robots_yellow();
      while (robots->size() < 1000) *robots->Add() = robots->Get(robots->size() % 6);
      break;
    }
    case Bad::camera_4e9:
      packet.mutable_detection()->set_camera_id(4000000000u);
      break;
    case Bad::zero_field:
    case Bad::negative_field: {
      packet = make_geometry_packet(FieldSize{9000, 6000});
      auto* field = packet.mutable_geometry()->mutable_field();
      if (kind == Bad::zero_field)
        field->set_field_length(0);
      else
        field->set_field_width(-6000);
      break;
    }
    case Bad::late_frame:
      packet = detections[detections.size() - 2];
      break;
    case Bad::old_frame:
      packet = detections[detections.size() - 6];
      break;
    case Bad::duplicate_frame:
      break;
    case Bad::other_message: {
      proto::FormationPrediction message;
      Formation formation;
      formation.time_s = last.detection().t_capture();
      Prediction prediction = predict(TransitionTable(Grid(3, 2)), formation, 2);
      const TransitionTable empty(Grid(3, 2));
      PredictionContext context;
      context.codec = &empty.codec();
      fill_prediction_message(formation, prediction, context, message);
      return message.SerializeAsString();
    }
    case Bad::count:
      break;
  }
  return packet.SerializeAsString();
}

// The clean stream with bad datagrams interleaved: after each clean detection frame one bad
// datagram, of the kinds in turn (the old frame only where five frames exist, and never two
// old frames within six formations, so they stay stray frames, not a second clock).
DirtyStream dirty_stream(const std::vector<SSL_WrapperPacket>& clean, std::uint64_t seed) {
  DirtyStream out;
  std::mt19937_64 random(seed);
  std::vector<SSL_WrapperPacket> detections;
  int next_kind = 0;
  auto add = [&](const std::string& bytes) {
    out.datagrams.push_back(bytes);
    SSL_WrapperPacket packet;
    if (packet.ParsePartialFromString(bytes) && packet.IsInitialized()) {
      out.decodable.push_back(std::move(packet));
    } else {
      ++out.parse_errors;
    }
  };
  for (const SSL_WrapperPacket& packet : clean) {
    if (!packet.has_detection()) {
      add(packet.SerializeAsString());
      continue;
    }
    detections.push_back(packet);
    if (detections.size() % 3 == 0) {
      // Duplicate ids: every robot once more, elsewhere, with a lower confidence (the sampler
      // keeps the more confident report, so this is still the clean frame).
      SSL_WrapperPacket doubled = packet;
      auto* robots = doubled.mutable_detection()->mutable_robots_yellow();
      const int n = robots->size();
      for (int i = 0; i < n; ++i) {
        SSL_DetectionRobot copy = robots->Get(i);
        copy.set_confidence(copy.confidence() * 0.5F);
        copy.set_x(-copy.x());
        *robots->Add() = copy;
      }
      add(doubled.SerializeAsString());
      ++out.duplicate_id_packets;
    } else {
      add(packet.SerializeAsString());
    }
    if (detections.size() < 6) continue;
    auto kind = static_cast<Bad>(next_kind);
    next_kind = (next_kind + 1) % static_cast<int>(Bad::count);
    add(bad_datagram(kind, random, detections));
    ++out.sent[static_cast<int>(kind)];
  }
  return out;
}

TEST(Reliability, BadInputIsCountedAndChangesNothing) {
  TempDir dir;
  simulation::SimulationConfig simulation;
  simulation.seed = 41;
  const std::vector<SSL_WrapperPacket> clean = simulated_packets(simulation, 400);
  const DirtyStream dirty = dirty_stream(clean, 6);

  // References: the clean stream's table and predictions, and the dirty stream through the
  // library (what the daemons must count).
  const auto clean_training = train(clean);
  const auto dirty_training = train(dirty.decodable);
  ASSERT_EQ(entries(dirty_training->stored_table().table),
            entries(clean_training->stored_table().table))
      << "the library itself is disturbed by the bad input";
  const SamplerCounters& expected = dirty_training->sampler().counters();
  simulation::SimulationConfig table_simulation;
  table_simulation.seed = 3;
  const auto predictor_training = train(simulated_packets(table_simulation, 2000));
  const StoredTable predictor_stored = predictor_training->stored_table();
  const TransitionTable& predictor_table = predictor_stored.table;
  ASSERT_TRUE(save_table(dir / "fixed.bin", predictor_table, TableMetadata{}));
  const std::vector<std::string> expected_predictions = library_predictions(clean, predictor_table);
  ASSERT_EQ(expected_predictions.size(), clean_training->sampler().counters().samples);

  RunningPipeline pipeline(dir, dir / "fixed.bin");
  ASSERT_TRUE(pipeline.ready());
  ChildProcess& trainer = pipeline.trainer;
  ChildProcess& predictor = pipeline.predictor;
  PredictionListener listener(pipeline.predictions);
  send_paced(pipeline.vision, dirty.datagrams);
  if (HasFatalFailure()) return;
  const auto received = listener.wait_for_bytes(expected_predictions.size(), 15s);
  ASSERT_TRUE(wait_for_status(trainer, "formations", expected.samples, 10s))
      << trainer.stderr_text();
  ASSERT_TRUE(wait_for_status(predictor, "packets", dirty.datagrams.size(), 10s))
      << predictor.stderr_text();
  trainer.signal(SIGTERM);
  predictor.signal(SIGTERM);
  EXPECT_EQ(trainer.wait(5s), 0) << trainer.stderr_text();
  EXPECT_EQ(predictor.wait(5s), 0) << predictor.stderr_text();

  // Every datagram arrived and was counted, by kind.
  const auto t = last_status(trainer.stderr_text());
  EXPECT_EQ(t.at("packets"), dirty.datagrams.size());
  EXPECT_EQ(t.at("kernel_drops"), 0u);
  EXPECT_EQ(t.at("parse_errors"), dirty.parse_errors);
  EXPECT_EQ(t.at("non_finite"), expected.robots_non_finite);
  EXPECT_EQ(t.at("out_of_range"), expected.robots_out_of_range);
  EXPECT_EQ(t.at("duplicate_ids"), expected.robots_duplicate_in_frame);
  EXPECT_EQ(t.at("bad_camera"), expected.frames_bad_camera);
  EXPECT_EQ(t.at("too_many_robots"), expected.frames_too_many_robots);
  EXPECT_EQ(t.at("late"), expected.frames_late);
  EXPECT_EQ(t.at("duplicate_frames"), expected.frames_duplicate);
  EXPECT_EQ(t.at("other_clock"), expected.frames_other_clock);
  EXPECT_EQ(t.at("bad_geometry"), expected.geometry_invalid);
  EXPECT_EQ(t.at("empty_packets"), expected.packets_empty);
  EXPECT_EQ(t.at("clock_conflicts"), 0u);
  EXPECT_EQ(t.at("clock_resets"), 0u);
  // Each kind really happened and was counted.
  EXPECT_GT(dirty.parse_errors, dirty.sent[static_cast<int>(Bad::truncated)] / 2);
  EXPECT_GT(expected.robots_non_finite, 0u);
  EXPECT_GT(expected.robots_out_of_range, 0u);
  EXPECT_GT(expected.robots_duplicate_in_frame, 0u);
  EXPECT_EQ(expected.frames_bad_camera, dirty.sent[static_cast<int>(Bad::camera_4e9)]);
  EXPECT_EQ(expected.frames_too_many_robots, dirty.sent[static_cast<int>(Bad::thousand_robots)]);
  EXPECT_EQ(expected.frames_late, dirty.sent[static_cast<int>(Bad::late_frame)]);
  EXPECT_EQ(expected.frames_other_clock, dirty.sent[static_cast<int>(Bad::old_frame)]);
  EXPECT_EQ(expected.geometry_invalid, dirty.sent[static_cast<int>(Bad::zero_field)] +
                                           dirty.sent[static_cast<int>(Bad::negative_field)]);
  EXPECT_GE(expected.frames_duplicate, dirty.sent[static_cast<int>(Bad::duplicate_frame)]);
  // One warning per kind in the trainer's log.
  for (const char* key :
       {"[non_finite]", "[out_of_range]", "[duplicate_ids]", "[bad_camera]", "[too_many_robots]",
        "[late]", "[duplicate_frames]", "[other_clock]", "[bad_geometry]"}) {
    EXPECT_NE(trainer.stderr_text().find(key), std::string::npos) << key;
  }

  // The trainer's table is the clean stream's.
  const auto loaded = load_table(dir / "trainer.bin", Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(entries(loaded->table), entries(clean_training->stored_table().table));
  EXPECT_EQ(loaded->metadata.samples, clean_training->samples());

  // The predictor's predictions are the clean stream's.
  const auto p = last_status(predictor.stderr_text());
  EXPECT_EQ(p.at("packets"), dirty.datagrams.size());
  EXPECT_EQ(p.at("parse_errors"), dirty.parse_errors);
  EXPECT_EQ(p.at("kernel_drops"), 0u);
  EXPECT_EQ(p.at("non_finite"), expected.robots_non_finite);
  EXPECT_EQ(p.at("bad_camera"), expected.frames_bad_camera);
  EXPECT_EQ(p.at("other_clock"), expected.frames_other_clock);
  EXPECT_EQ(p.at("duplicate_frames"), expected.frames_duplicate);
  ASSERT_EQ(received.size(), expected_predictions.size());
  for (std::size_t i = 0; i < received.size(); ++i) {
    ASSERT_EQ(received[i], expected_predictions[i]) << "prediction " << i;
  }

  std::cout << "[ figures  ] bad datagrams sent:";
  for (int k = 0; k < static_cast<int>(Bad::count); ++k)
    std::cout << " " << bad_names[k] << "=" << dirty.sent[k];
  std::cout << "; clean datagrams="
            << dirty.datagrams.size() -
                   std::accumulate(dirty.sent.begin(), dirty.sent.end(), std::size_t{0})
            << " (of which duplicate-id frames=" << dirty.duplicate_id_packets << ")"
            << " parse_errors=" << dirty.parse_errors << " formations=" << expected.samples
            << " transitions=" << clean_training->stored_table().table.transitions() << "\n";
}

}  // namespace
}  // namespace ssl_formation::reliability
