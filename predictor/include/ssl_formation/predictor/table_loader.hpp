#pragma once
// The table's loader thread. Reading a table file and building what the model predicts from
// (PredictionPipeline::prepare_table: the motion model's index) takes about a second for a 40 MB
// table; on the thread that predicts, that second was a gap in the predictions every time the
// trainer saved. Here it happens on a thread of its own: the predicting thread asks for a look at
// the file, goes on predicting from the table it has, and takes the prepared table when it is
// ready, to install it between two frames (a few pointer moves). The table it replaces comes
// back here to be freed, which for a large model also takes milliseconds.
//
// One look at a time: a look asked for while one is under way follows it, so a file replaced
// during a load is loaded again after it.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ssl_formation/base/grid.hpp"
#include "ssl_formation/model_api/model.hpp"
#include "ssl_formation/models/table_file.hpp"
#include "ssl_formation/predictor/table_watcher.hpp"

namespace ssl_formation::predictor {

class TableLoader {
 public:
  // Prepares a table the file gave, on the loader's thread (PredictionPipeline::prepare_table);
  // throws std::invalid_argument for a table the model cannot use.
  using Prepare = std::function<PreparedTable(std::shared_ptr<const StoredTable>)>;

  // What a look at the file came to, handed over in the order the looks happened.
  struct Outcome {
    enum class Kind {
      loaded,      // `prepared` is ready to install
      unreadable,  // the file did not load (`error`, the watcher's)
      refused,     // it loaded, but the model cannot use it (`error`, prepare's)
      absent,      // no file yet: only said of the first look at a file
    };
    Kind kind = Kind::absent;
    std::filesystem::path path;
    PreparedTable prepared;
    std::string error;
    // The tables loaded from this file so far, refused ones included (TableWatcher::reloads).
    std::uint64_t reloads = 0;
    bool first_look = false;
  };

  // Starts the thread; it looks at `path` only when asked (look()).
  TableLoader(std::filesystem::path path, Grid grid, TableFileLoader load, Prepare prepare);
  TableLoader(const TableLoader&) = delete;
  TableLoader& operator=(const TableLoader&) = delete;
  ~TableLoader() { stop(); }

  // Asks for a look at the file, and returns at once.
  void look();
  // Follows another file from now on (the next opponent's table): what comes of the file before
  // is dropped, even a load under way.
  void follow(std::filesystem::path path);
  // Whether an outcome waits to be taken: one atomic load, for the prediction's path.
  bool has_outcome() const noexcept { return has_outcome_.load(std::memory_order_acquire); }
  std::optional<Outcome> take();
  // Waits until no look is asked for or under way; false if `timeout` passed first.
  bool wait_idle(
      std::chrono::steady_clock::duration timeout = std::chrono::steady_clock::duration::max());
  // Frees a table the pipeline no longer uses on the loader's thread.
  void release(PreparedTable old);
  // Stops the thread and joins it; outcomes not taken are dropped. A look under way is not cut
  // short in its file read (load_table cannot be interrupted), but it skips the prepare step
  // after it, so stopping waits for one file read at the most.
  void stop();

 private:
  void run();
  // One look, without the lock; none when there is nothing to say.
  std::optional<Outcome> look_once(TableWatcher& watcher, bool first_look);

  const Grid grid_;
  const TableFileLoader load_;
  const Prepare prepare_;

  std::mutex mutex_;
  std::condition_variable wake_;  // the thread's: a look, something to free, or stop
  std::condition_variable idle_;  // wait_idle's
  // Under mutex_:
  std::filesystem::path path_;
  std::uint64_t generation_ = 0;  // one more at each follow(): outcomes of older ones are dropped
  bool asked_ = false;
  bool busy_ = false;
  std::deque<Outcome> outcomes_;
  std::vector<PreparedTable> to_release_;

  std::atomic<bool> has_outcome_{false};
  std::atomic<bool> stopping_{false};
  std::thread thread_;  // last: started once everything it uses exists
};

}  // namespace ssl_formation::predictor
