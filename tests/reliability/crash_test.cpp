// Crash safety (issue 6, part 3): the trainer is killed with SIGKILL at 50 random moments while a
// producer feeds it and it saves every 20 ms. After each kill the table loads, its checksum holds,
// it holds at least the last save the trainer logged, and counts never go down from one kill to
// the next (the trainer restarts on the same table each time and resumes every count in it). The
// simulated feed jumps between formations every 2 s: the paper's model (--model paper) counts it.

#include <signal.h>

#include <iostream>
#include <optional>
#include <random>

#include "reliability_support.hpp"

namespace ssl_formation::reliability {
namespace {

using testing::ChildProcess;
using testing::TempDir;

struct Saved {
  std::uint64_t transitions = 0;
  std::uint64_t formations = 0;
  int saves = 0;
};

// The last "saved PATH (N transitions, M formations)" line the trainer completed.
Saved last_logged_save(const std::string& log) {
  static const std::regex saved(R"(saved \S+ \((\d+) transitions, (\d+) formations\)\n)");
  Saved out;
  for (std::sregex_iterator it(log.begin(), log.end(), saved), end; it != end; ++it) {
    out.transitions = std::stoull((*it)[1]);
    out.formations = std::stoull((*it)[2]);
    ++out.saves;
  }
  return out;
}

std::size_t temporaries(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().filename().string().find(".tmp-") != std::string::npos) ++n;
  }
  return n;
}

TEST(Reliability, TrainerKilledFiftyTimesWhileSavingLosesNoSavedCount) {
  TempDir dir;
  const std::string group = new_group();
  const auto table_path = dir / "table.bin";
  // 500 formations a second for at most 120 s; the destructor stops it when the test is done.
  ChildProcess producer(
      producer_program,
      {"--simulation", "paper", "--referee", "off", "--vision-address", group, "--seed", "51",
       "--period", "0.002", "--count", "60000", "--status-interval", "100"},
      dir.path(), "producer");
  std::mt19937_64 random(20240601);
  std::uniform_int_distribution<int> delay_ms(5, 400);
  std::uint64_t previous_transitions = 0;
  std::uint64_t previous_formations = 0;
  int kills = 0;
  int total_saves = 0;
  std::size_t most_temporaries = 0;
  const auto started = std::chrono::steady_clock::now();
  for (int round = 0; round < 50; ++round) {
    // What this round starts from: the table file as the last kill left it, if any (round 0, and
    // a round after kills that all came before the first save, start without one).
    std::optional<StoredTable> before;
    if (std::filesystem::exists(table_path)) {
      auto loaded = load_table(table_path, Grid(3, 2));
      ASSERT_TRUE(loaded) << "before round " << round << ": " << loaded.error().message;
      before = std::move(*loaded);
    }
    ChildProcess trainer(
        trainer_program,
        {"--vision-address", group, "--table", table_path.string(), "--flush-interval", "0.02",
         "--status-interval", "100", "--verbose", "--model", "paper"},
        dir.path(), "trainer-" + std::to_string(round), testing::Readiness::ready_file);
    ASSERT_TRUE(trainer.wait_until_ready(10s)) << trainer.stderr_text();
    // Ready means the table is open: the trainer resumed exactly what the file holds (and said
    // so), or, without a file, started an empty table.
    const std::string resumed = "resumed " + table_path.string() + ": grid 3x2, ";
    if (before) {
      EXPECT_NE(trainer.stderr_text().find(
                    resumed + std::to_string(before->table.transitions()) + " transitions, " +
                    std::to_string(before->metadata.samples) + " formations"),
                std::string::npos)
          << "round " << round << ":\n"
          << trainer.stderr_text();
    } else {
      EXPECT_EQ(trainer.stderr_text().find("resumed "), std::string::npos)
          << "round " << round << " resumed a table that does not exist:\n"
          << trainer.stderr_text();
    }
    ASSERT_TRUE(producer.running());
    // The kill moment itself is the scenario: a random instant 5 to 400 ms into the run, so the
    // 50 kills land before, between and in the middle of the 20 ms saves.
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(random)));
    trainer.signal(SIGKILL);
    int signalled = 0;
    ASSERT_FALSE(trainer.wait(5s, &signalled).has_value());
    ASSERT_EQ(signalled, SIGKILL);
    ++kills;

    const Saved logged = last_logged_save(trainer.stderr_text());
    total_saves += logged.saves;
    most_temporaries = std::max(most_temporaries, temporaries(dir.path()));
    if (!std::filesystem::exists(table_path)) {
      ASSERT_EQ(logged.saves, 0) << "a save was logged but there is no table";
      continue;
    }
    const auto loaded = load_table(table_path, Grid(3, 2));
    ASSERT_TRUE(loaded) << "after kill " << round << ": " << loaded.error().message;
    const std::uint64_t transitions = loaded->table.transitions();
    const std::uint64_t formations = loaded->metadata.samples;
    if (logged.saves > 0) {
      EXPECT_GE(transitions, logged.transitions) << "kill " << round << " lost a logged save";
      EXPECT_GE(formations, logged.formations) << "kill " << round;
    }
    if (before) {
      // Resumed, not restarted: every count of the table the round started from is still there.
      std::size_t lower = 0;
      before->table.for_each_nonzero([&](StateIndex from, StateIndex to, TransitionTable::Count c) {
        if (loaded->table.count(from, to) < c) ++lower;
      });
      EXPECT_EQ(lower, 0u) << "kill " << round << ": counts of the table it resumed went down";
    }
    EXPECT_GE(transitions, previous_transitions) << "kill " << round << ": counts went down";
    EXPECT_GE(formations, previous_formations) << "kill " << round;
    previous_transitions = transitions;
    previous_formations = formations;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  EXPECT_GT(previous_transitions, 0u);
  EXPECT_GT(total_saves, 50);
  // A kill mid-save leaves at most its own temporary file; the next trainer removes it.
  EXPECT_LE(most_temporaries, 1u);
  std::cout << "[ figures  ] kills=" << kills << " saves_logged=" << total_saves
            << " final_transitions=" << previous_transitions
            << " final_formations=" << previous_formations
            << " most_leftover_temporaries=" << most_temporaries << " seconds=" << seconds << "\n";
}

}  // namespace
}  // namespace ssl_formation::reliability
