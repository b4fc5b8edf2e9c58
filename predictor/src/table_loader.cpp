#include "ssl_formation/predictor/table_loader.hpp"

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace ssl_formation::predictor {

TableLoader::TableLoader(std::filesystem::path path, Grid grid, TableFileLoader load,
                         Prepare prepare)
    : grid_(grid),
      load_(std::move(load)),
      prepare_(std::move(prepare)),
      path_(std::move(path)),
      thread_([this] { run(); }) {}

void TableLoader::look() {
  {
    const std::lock_guard lock(mutex_);
    asked_ = true;
  }
  wake_.notify_one();
}

void TableLoader::follow(std::filesystem::path path) {
  std::deque<Outcome> dropped;
  {
    const std::lock_guard lock(mutex_);
    path_ = std::move(path);
    ++generation_;
    dropped.swap(outcomes_);
    has_outcome_.store(false, std::memory_order_release);
    // The dropped tables are freed on the loader's thread too.
    for (Outcome& outcome : dropped) to_release_.push_back(std::move(outcome.prepared));
  }
  wake_.notify_one();
}

std::optional<TableLoader::Outcome> TableLoader::take() {
  const std::lock_guard lock(mutex_);
  if (outcomes_.empty()) return std::nullopt;
  Outcome outcome = std::move(outcomes_.front());
  outcomes_.pop_front();
  has_outcome_.store(!outcomes_.empty(), std::memory_order_release);
  return outcome;
}

bool TableLoader::wait_idle(std::chrono::steady_clock::duration timeout) {
  std::unique_lock lock(mutex_);
  const auto idle = [this] { return (!asked_ && !busy_) || stopping_.load(); };
  if (timeout == std::chrono::steady_clock::duration::max()) {
    idle_.wait(lock, idle);
    return true;
  }
  return idle_.wait_for(lock, timeout, idle);
}

void TableLoader::release(PreparedTable old) {
  if (!old.table && !old.built) return;
  {
    const std::lock_guard lock(mutex_);
    to_release_.push_back(std::move(old));
  }
  wake_.notify_one();
}

void TableLoader::stop() {
  {
    const std::lock_guard lock(mutex_);
    stopping_.store(true);
  }
  wake_.notify_one();
  idle_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void TableLoader::run() {
  // Below the thread that predicts: on a machine with as many busy threads as cores, a table
  // ready a little later costs nothing, a frame predicted late does. Lowering needs no
  // privilege; where the call is refused (a sandbox), the thread keeps the process's priority.
  const auto self = static_cast<id_t>(::gettid());
  ::setpriority(PRIO_PROCESS, self, std::min(::getpriority(PRIO_PROCESS, self) + 10, 19));
  // Lives on this thread only: a look runs without the lock.
  std::optional<TableWatcher> watcher;
  std::uint64_t watched_generation = 0;
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stopping_.load() || asked_ || !to_release_.empty(); });
    if (!to_release_.empty()) {
      // Freed without the lock: the predicting thread may want it meanwhile.
      std::vector<PreparedTable> garbage = std::exchange(to_release_, {});
      lock.unlock();
      garbage.clear();
      // A 40 MB table and its model are over 100 MB in many blocks, freed into this thread's
      // malloc arena, which keeps them: without the trim the process grew to about 550 MB over
      // 20 reloads, where freeing them on the main thread had kept it at 360 MB.
      ::malloc_trim(0);
      lock.lock();
      continue;
    }
    if (stopping_.load()) break;
    asked_ = false;
    busy_ = true;
    bool first_look = false;
    if (!watcher || watched_generation != generation_) {
      watcher.emplace(path_, grid_, load_);
      watched_generation = generation_;
      first_look = true;
    }
    lock.unlock();
    std::optional<Outcome> outcome = look_once(*watcher, first_look);
    lock.lock();
    busy_ = false;
    if (outcome && watched_generation == generation_ && !stopping_.load()) {
      outcomes_.push_back(std::move(*outcome));
      has_outcome_.store(true, std::memory_order_release);
    } else if (outcome) {
      to_release_.push_back(std::move(outcome->prepared));  // freed at the loop's next turn
    }
    idle_.notify_all();
  }
  lock.unlock();
  idle_.notify_all();
}

std::optional<TableLoader::Outcome> TableLoader::look_once(TableWatcher& watcher, bool first_look) {
  Outcome outcome;
  outcome.path = watcher.path();
  outcome.first_look = first_look;
  TableWatcher::Change change = TableWatcher::Change::none;
  try {
    change = watcher.poll();
  } catch (const std::exception& error) {
    // A bad file never stops the daemon: whatever the read throws (no memory for a huge table)
    // is reported as a file that did not load.
    outcome.kind = Outcome::Kind::unreadable;
    outcome.error = watcher.path().string() + ": " + error.what();
    outcome.reloads = watcher.reloads();
    return outcome;
  }
  switch (change) {
    case TableWatcher::Change::none:
      if (!first_look) return std::nullopt;
      outcome.kind = Outcome::Kind::absent;
      break;
    case TableWatcher::Change::failed:
      outcome.kind = Outcome::Kind::unreadable;
      outcome.error = watcher.last_error();
      break;
    case TableWatcher::Change::loaded:
      if (stopping_.load()) return std::nullopt;
      try {
        outcome.prepared = prepare_(watcher.table());
        outcome.kind = Outcome::Kind::loaded;
      } catch (const std::exception& error) {
        outcome.kind = Outcome::Kind::refused;
        outcome.error = error.what();
      }
      break;
  }
  outcome.reloads = watcher.reloads();
  return outcome;
}

}  // namespace ssl_formation::predictor
