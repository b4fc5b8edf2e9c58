#include "ssl_formation/trainer/table_saver.hpp"

#include <utility>

namespace ssl_formation::trainer {

TableSaver::TableSaver(SaveHooks hooks) : hooks_(std::move(hooks)), thread_([this] { run(); }) {}

TableSaver::~TableSaver() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void TableSaver::submit(const std::filesystem::path& path, TableSnapshot snapshot,
                        const TableBudget& budget) {
  {
    const std::lock_guard lock(mutex_);
    pending_.insert_or_assign(path, Job{std::move(snapshot), budget});
  }
  changed_.notify_all();
}

bool TableSaver::wait() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return pending_.empty() && !busy_; });
  const bool ok = !failed_;
  failed_ = false;
  return ok;
}

std::uint64_t TableSaver::saved() const {
  const std::lock_guard lock(mutex_);
  return saved_;
}

void TableSaver::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return stopping_ || !pending_.empty(); });
    if (pending_.empty()) return;  // stopping, and nothing left to save
    auto next = pending_.extract(pending_.begin());
    busy_ = true;
    lock.unlock();
    const bool ok =
        save_snapshot(next.key(), next.mapped().snapshot, next.mapped().budget, hooks_).has_value();
    lock.lock();
    busy_ = false;
    failed_ = failed_ || !ok;
    ++saved_;
    changed_.notify_all();
  }
}

}  // namespace ssl_formation::trainer
