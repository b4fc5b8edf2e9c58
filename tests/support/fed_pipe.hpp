#pragma once
// A pipe with a thread writing given bytes into it, named as a shell's process substitution
// names one (/dev/fd/N): what a reader gets from `ssl-trainer --from-log <(zcat day.log.gz)`.
// Whatever the reader leaves unread is drained on destruction, so the feeder always ends.

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <thread>

namespace ssl_formation::testing {

class FedPipe {
 public:
  explicit FedPipe(std::string bytes) : bytes_(std::move(bytes)) {
    if (::pipe(ends_) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
    feeder_ = std::thread([this] {
      for (std::size_t at = 0; at < bytes_.size();) {
        const ssize_t wrote = ::write(ends_[1], bytes_.data() + at, bytes_.size() - at);
        if (wrote <= 0) break;
        at += static_cast<std::size_t>(wrote);
      }
      ::close(ends_[1]);
    });
  }
  FedPipe(const FedPipe&) = delete;
  FedPipe& operator=(const FedPipe&) = delete;
  ~FedPipe() {
    char sink[4096];
    while (::read(ends_[0], sink, sizeof sink) > 0) {
    }
    ::close(ends_[0]);
    feeder_.join();
  }

  std::string path() const { return "/dev/fd/" + std::to_string(ends_[0]); }

 private:
  std::string bytes_;
  int ends_[2] = {-1, -1};
  std::thread feeder_;
};

}  // namespace ssl_formation::testing
