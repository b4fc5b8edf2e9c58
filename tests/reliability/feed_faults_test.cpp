// Feed faults (issue 6, part 4), in the library and end to end: the feed stops for 30 s of data
// time and comes back, the field switches from Division B to Division A geometry, t_capture
// jumps backwards, and a second sender joins the group with a clock of its own. No crash, and no
// transition is ever counted across a fault: each stream after a fault trains exactly as if it
// had been a separate stream, and two interleaved clocks count nothing while they interleave.

#include <signal.h>

#include <iostream>

#include "reliability_support.hpp"

namespace ssl_formation::reliability {
namespace {

using testing::ChildProcess;
using testing::TempDir;

using Formations = std::vector<std::vector<SSL_WrapperPacket>>;

const FieldSize division_a{12000, 9000};

// The packets of each simulated formation, one vector per formation.
Formations formations(std::uint64_t seed, int count, double start_time_s,
                      FieldSize field = {9000, 6000}) {
  simulation::SimulationConfig config;
  config.seed = seed;
  config.start_time_s = start_time_s;
  config.field = field;
  simulation::SimulatedVision vision(config);
  Formations out;
  for (int i = 0; i < count; ++i) out.push_back(vision.next().packets);
  return out;
}

std::vector<SSL_WrapperPacket> flat(const Formations& f, std::size_t from = 0,
                                    std::size_t to = SIZE_MAX) {
  std::vector<SSL_WrapperPacket> out;
  for (std::size_t i = from; i < std::min(to, f.size()); ++i)
    out.insert(out.end(), f[i].begin(), f[i].end());
  return out;
}

std::vector<SSL_WrapperPacket> concat(std::initializer_list<std::vector<SSL_WrapperPacket>> parts) {
  std::vector<SSL_WrapperPacket> out;
  for (const auto& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

// The segments trained as separate streams (start_new_stream between them): no transition
// across a boundary, and nothing else lost.
TransitionTable separately(std::initializer_list<std::vector<SSL_WrapperPacket>> segments) {
  Training training(SamplerConfig{}, TransitionTable(Grid(3, 2)));
  for (const auto& segment : segments) {
    training.start_new_stream();
    for (const auto& packet : segment) training.add(packet);
  }
  return training.stored_table().table;
}

TEST(ReliabilityFeedFaults, FeedStoppingForThirtySecondsOfDataTimeCountsNothingAcrossTheGap) {
  const auto before = flat(formations(61, 40, 0.0));   // t = 0 .. 78
  const auto after = flat(formations(62, 40, 110.0));  // t = 110 .. 188: 30 s missing
  const auto training = train(concat({before, after}));
  EXPECT_EQ(entries(training->stored_table().table), entries(separately({before, after})));
  EXPECT_EQ(training->sampler().counters().clock_resets, 1u);
  EXPECT_EQ(training->sampler().counters().samples, 80u);  // nothing after the gap is lost
  // A gap shorter than two steps (one missing formation) is a chain break, not a new clock.
  const auto short_gap = train(concat({before, flat(formations(62, 40, 82.0))}));
  EXPECT_EQ(entries(short_gap->stored_table().table),
            entries(separately({before, flat(formations(62, 40, 82.0))})));
  EXPECT_EQ(short_gap->sampler().counters().clock_resets, 0u);
}

TEST(ReliabilityFeedFaults, DivisionBToDivisionAGeometryMidStreamCountsNothingAcrossTheChange) {
  const auto division_b = flat(formations(61, 40, 0.0));
  const auto then_a = flat(formations(63, 40, 80.0, division_a));
  const auto training = train(concat({division_b, then_a}));
  EXPECT_EQ(entries(training->stored_table().table), entries(separately({division_b, then_a})));
  EXPECT_EQ(training->sampler().counters().field_changes, 1u);
  EXPECT_EQ(training->sampler().field(), division_a);
  EXPECT_EQ(training->sampler().counters().samples, 80u);
}

TEST(ReliabilityFeedFaults, TimeJumpingBackwardsStartsANewStream) {
  const auto first = flat(formations(61, 40, 1000.0));  // t = 1000 .. 1078
  const auto back = flat(formations(64, 40, 900.0));    // jumps back 178 s
  const auto training = train(concat({first, back}));
  EXPECT_EQ(entries(training->stored_table().table), entries(separately({first, back})));
  EXPECT_EQ(training->sampler().counters().clock_resets, 1u);
  EXPECT_EQ(training->sampler().counters().samples, 80u);
  // A step back of less than two steps looks like reordering: the frames older than the last
  // sample are dropped as late, and nothing is counted twice.
  const auto slightly = train(concat({first, flat(formations(64, 40, 1077.0))}));
  EXPECT_EQ(slightly->sampler().counters().clock_resets, 0u);
  EXPECT_GE(slightly->sampler().counters().frames_late, 1u);
  EXPECT_LE(slightly->stored_table().table.transitions(),
            separately({first, flat(formations(64, 40, 1077.0))}).transitions());
}

// A (t from 0) runs 120 formations; B (t from 5000) interleaves formation by formation with A's
// formations 40-79, as a replay started beside the live feed would.
std::vector<SSL_WrapperPacket> two_senders(const Formations& a, const Formations& b) {
  std::vector<SSL_WrapperPacket> out = flat(a, 0, 40);
  for (std::size_t i = 40; i < 80; ++i) {
    out.insert(out.end(), a[i].begin(), a[i].end());
    out.insert(out.end(), b[i - 40].begin(), b[i - 40].end());
  }
  const auto rest = flat(a, 80);
  out.insert(out.end(), rest.begin(), rest.end());
  return out;
}

TEST(ReliabilityFeedFaults, ASecondSenderIsAClockConflictThatCountsNoTransition) {
  const Formations a = formations(61, 120, 0.0);
  const Formations b = formations(65, 40, 5000.0);
  std::vector<std::pair<double, std::size_t>> samples;  // time, transitions
  Training training(SamplerConfig{}, TransitionTable(Grid(3, 2)));
  FormationSampler sampler(SamplerConfig{}, [&](const FormationSample& sample) {
    samples.emplace_back(sample.formation.time_s, sample.transitions.size());
  });
  for (const auto& packet : two_senders(a, b)) {
    training.add(packet);
    sampler.add(packet);
  }
  const SamplerCounters& c = sampler.counters();
  EXPECT_EQ(c.clock_conflicts, 1u);
  EXPECT_EQ(c.clock_resets, 0u);         // no thrashing between the two clocks
  EXPECT_EQ(c.frames_other_clock, 40u);  // every frame of B set aside
  EXPECT_EQ(c.samples, 120u);            // every formation of A sampled
  std::size_t quiet = 0;
  for (const auto& [time_s, transitions] : samples) {
    EXPECT_LT(time_s, 5000.0);  // nothing sampled from B's clock
    // From B's second frame (the clock advances: a second sender, not a stray frame) until
    // B has been silent for four steps, nothing is counted.
    if (time_s >= 2.0 * 42 && time_s <= 2.0 * 79 + 8.0) {
      EXPECT_EQ(transitions, 0u) << "at t=" << time_s;
      ++quiet;
    }
  }
  EXPECT_EQ(quiet, 42u);
  EXPECT_EQ(c.samples_in_conflict, 42u);
  // Only A was counted, and less of it than A alone holds (the conflict's samples count nothing).
  EXPECT_LT(training.stored_table().table.transitions(),
            train(flat(a))->stored_table().table.transitions());
}

TEST(ReliabilityFeedFaults, AStrayOldFrameIsNeitherARestartNorAConflict) {
  const Formations a = formations(61, 40, 0.0);
  std::vector<SSL_WrapperPacket> stream = flat(a, 0, 20);
  stream.push_back(a[10].back());  // twenty seconds old
  stream.push_back(a[10].back());  // and again
  stream.push_back(a[30].back());  // twenty seconds ahead: a bad clock
  const auto rest = flat(a, 20);
  stream.insert(stream.end(), rest.begin(), rest.end());
  const auto training = train(stream);
  EXPECT_EQ(entries(training->stored_table().table), entries(train(flat(a))->stored_table().table));
  EXPECT_EQ(training->sampler().counters().frames_other_clock, 3u);
  EXPECT_EQ(training->sampler().counters().clock_resets, 0u);
  EXPECT_EQ(training->sampler().counters().clock_conflicts, 0u);
}

// Every fault in one stream, through the running daemons: the trainer's table and the
// predictor's predictions equal the library's on the same packets, and the daemons say which
// faults they saw.
TEST(ReliabilityFeedFaults, DaemonsSurviveEveryFaultAndAgreeWithTheLibrary) {
  TempDir dir;
  const auto stream = concat({
      flat(formations(61, 40, 0.0)),                // t 0 .. 78
      flat(formations(62, 40, 110.0)),              // 30 s gap
      flat(formations(63, 40, 190.0, division_a)),  // Division A geometry
      flat(formations(64, 40, 100.0, division_a)),  // t jumps back 168 s
      two_senders(formations(65, 120, 180.0, division_a), formations(66, 40, 9000.0, division_a)),
  });
  const auto expected = train(stream);
  const SamplerCounters& c = expected->sampler().counters();
  ASSERT_EQ(c.clock_resets, 2u);
  ASSERT_EQ(c.clock_conflicts, 1u);
  ASSERT_EQ(c.field_changes, 1u);
  ASSERT_EQ(c.samples, 280u);
  simulation::SimulationConfig table_simulation;
  table_simulation.seed = 3;
  const auto fixed = train(simulated_packets(table_simulation, 2000));
  ASSERT_TRUE(save_table(dir / "fixed.bin", fixed->stored_table().table, TableMetadata{}));
  const auto expected_predictions = library_predictions(stream, fixed->stored_table().table);

  RunningPipeline pipeline(dir, dir / "fixed.bin");
  ASSERT_TRUE(pipeline.ready());
  ChildProcess& trainer = pipeline.trainer;
  ChildProcess& predictor = pipeline.predictor;
  PredictionListener listener(pipeline.predictions);
  send_paced(pipeline.vision, stream);
  if (HasFatalFailure()) return;
  const auto received = listener.wait_for_bytes(expected_predictions.size(), 10s);
  ASSERT_TRUE(wait_for_status(trainer, "formations", c.samples, 10s)) << trainer.stderr_text();
  trainer.signal(SIGTERM);
  predictor.signal(SIGTERM);
  EXPECT_EQ(trainer.wait(5s), 0) << trainer.stderr_text();
  EXPECT_EQ(predictor.wait(5s), 0) << predictor.stderr_text();

  const auto status = last_status(trainer.stderr_text());
  EXPECT_EQ(status.at("packets"), stream.size());
  EXPECT_EQ(status.at("clock_resets"), 2u);
  EXPECT_EQ(status.at("clock_conflicts"), 1u);
  EXPECT_EQ(status.at("field_changes"), 1u);
  EXPECT_EQ(status.at("other_clock"), c.frames_other_clock);
  EXPECT_NE(trainer.stderr_text().find("[clock_conflicts]"), std::string::npos);
  const auto loaded = load_table(dir / "trainer.bin", Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(entries(loaded->table), entries(expected->stored_table().table));
  ASSERT_EQ(received.size(), expected_predictions.size());
  for (std::size_t i = 0; i < received.size(); ++i)
    ASSERT_EQ(received[i], expected_predictions[i]) << i;
  std::cout << "[ figures  ] faults: gap 30 s, Division B->A, back 168 s, second sender for 40 "
               "formations; "
            << "formations=" << c.samples
            << " transitions=" << expected->stored_table().table.transitions()
            << " clock_resets=" << c.clock_resets << " clock_conflicts=" << c.clock_conflicts
            << " set_aside=" << c.frames_other_clock
            << " samples_in_conflict=" << c.samples_in_conflict << "\n";
}

// Two real producers on one group, as a replay started beside the live feed: the trainer stays
// up, reports the conflict, and counts no more than the two streams hold on their own.
TEST(ReliabilityFeedFaults, TrainerBesideTwoRealProducersReportsTheConflict) {
  TempDir dir;
  const std::string group = new_group();
  // What the two producers send: the library's streams for their seeds and clocks.
  simulation::SimulationConfig config;
  config.seed = 71;
  const auto a_packets = simulated_packets(config, 300);
  const auto a = train(a_packets);
  config.seed = 72;
  config.start_time_s = 100000;
  const auto b_packets = simulated_packets(config, 300);
  const auto b = train(b_packets);
  ChildProcess trainer(trainer_program,
                       {"--vision-address", group, "--table", (dir / "trainer.bin").string(),
                        "--status-interval", "0.1", "--flush-interval", "60", "--model", "paper"},
                       dir.path(), "trainer", testing::Readiness::ready_file);
  ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
  auto producer = [&](const char* seed, const char* start) {
    return std::make_unique<ChildProcess>(
        producer_program,
        std::vector<std::string>{"--simulation", "paper", "--vision-address", group, "--seed", seed,
                                 "--start-time", start, "--period", "0.005", "--count", "300",
                                 "--status-interval", "100", "--referee", "off"},
        dir.path(), std::string("producer-") + seed);
  };
  auto live = producer("71", "0");
  auto replay = producer("72", "100000");
  ASSERT_EQ(live->wait(20s), 0);
  ASSERT_EQ(replay->wait(20s), 0);
  // Stopped once the trainer has taken in every datagram of both.
  const std::uint64_t sent = a_packets.size() + b_packets.size();
  ASSERT_TRUE(wait_for_status_where(
      trainer, [&](const testing::Status& s) { return received_or_dropped(s) >= sent; }, 10s))
      << "sent " << sent << "\n"
      << trainer.stderr_text();
  trainer.signal(SIGTERM);
  ASSERT_EQ(trainer.wait(5s), 0) << trainer.stderr_text();
  const auto status = last_status(trainer.stderr_text());
  EXPECT_GE(status.at("clock_conflicts"), 1u) << trainer.stderr_text();
  const auto loaded = load_table(dir / "trainer.bin", Grid(3, 2));
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_LT(loaded->table.transitions(),
            a->stored_table().table.transitions() + b->stored_table().table.transitions());
  std::cout << "[ figures  ] two producers: packets=" << status.at("packets")
            << " transitions=" << loaded->table.transitions()
            << " (alone: " << a->stored_table().table.transitions() << " + "
            << b->stored_table().table.transitions()
            << ") clock_conflicts=" << status.at("clock_conflicts")
            << " clock_resets=" << status.at("clock_resets")
            << " other_clock=" << status.at("other_clock") << "\n";
}

}  // namespace
}  // namespace ssl_formation::reliability
