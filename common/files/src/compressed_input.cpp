#include "ssl_formation/files/compressed_input.hpp"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <utility>

#include "zlib_errors.hpp"

#ifdef SSLF_HAVE_ISAL
#include <isa-l/igzip_lib.h>
#endif

namespace ssl_formation {
inline namespace files {

namespace {

// Compressed bytes read from the file at a time, by either inflater.
constexpr std::size_t kGzipInputSize = 128 * 1024;
// zlib reads a plain file through its own buffer too, unless a read asks for at least twice that
// buffer: with a small one, big reads land straight in the caller's buffer, one copy fewer.
constexpr unsigned kPlainBufferSize = 16 * 1024;
static_assert(CompressedInput::kDirectReadSize >= 2 * kPlainBufferSize);
// The most one gzread (an int count) or one isal_inflate (a uint32_t one) is asked for.
constexpr std::size_t kLargestRead = 1u << 30;

using FilePtr = std::unique_ptr<std::FILE, decltype([](std::FILE* file) { std::fclose(file); })>;

// What a path holds, as far as can be told without consuming any of it.
enum class FileKind { gzip, plain, unknown };

// A regular file is told by its first two bytes. Anything else (a pipe, a file that cannot be
// read: gzopen says why) is unknown: a pipe's bytes, once read here, would be gone, so zlib,
// which tells gzip from plain data as it reads, takes it.
FileKind kind_of(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return FileKind::unknown;
  const FilePtr file(std::fopen(path.c_str(), "rb"));
  if (!file) return FileKind::unknown;
  unsigned char magic[2] = {0, 0};
  const std::size_t got = std::fread(magic, 1, sizeof magic, file.get());
  return got == sizeof magic && magic[0] == 0x1f && magic[1] == 0x8b ? FileKind::gzip
                                                                     : FileKind::plain;
}

}  // namespace

class CompressedInput::Source {
 public:
  using Fault = CompressedInput::Fault;

  virtual ~Source() = default;
  virtual std::size_t read(char* buffer, std::size_t size) = 0;
  virtual std::uint64_t compressed_offset() const = 0;
  virtual Inflater inflater() const = 0;

  Fault fault() const { return fault_; }
  const std::string& fault_message() const { return fault_message_; }

 protected:
  void set_fault(Fault fault, std::string message = {}) {
    fault_ = fault;
    fault_message_ = std::move(message);
  }

 private:
  Fault fault_ = Fault::none;
  std::string fault_message_;
};

namespace {

// zlib's gzFile: inflates gzip data and reads anything else through as it is.
class ZlibSource final : public CompressedInput::Source {
 public:
  static Result<std::unique_ptr<Source>> open(const std::filesystem::path& path, FileKind kind) {
    errno = 0;
    gzFile file = gzopen(path.c_str(), "rb");
    if (file == nullptr) {
      return fail(path.string() + ": cannot open: " + detail::zlib_errno_text(errno));
    }
    // Before the first read, as zlib requires.
    gzbuffer(file, kind == FileKind::plain ? kPlainBufferSize : kGzipInputSize);
    return std::unique_ptr<Source>(new ZlibSource(path, file));
  }
  ~ZlibSource() override { gzclose(file_); }

  std::size_t read(char* buffer, std::size_t size) override {
    const int got = gzread(file_, buffer, static_cast<unsigned>(std::min(size, kLargestRead)));
    if (got > 0) return static_cast<std::size_t>(got);
    int code = Z_OK;
    const char* message = gzerror(file_, &code);
    // Z_BUF_ERROR: the gzip stream stops in the middle, i.e. the file was cut off.
    if (code == Z_BUF_ERROR) {
      set_fault(Fault::cut_off);
    } else if (code != Z_OK) {
      set_fault(Fault::damaged, detail::without_path(message != nullptr ? message : "", path_));
    }
    return 0;
  }
  std::uint64_t compressed_offset() const override {
    const auto at = gzoffset(file_);
    return at < 0 ? 0 : static_cast<std::uint64_t>(at);
  }
  Inflater inflater() const override { return Inflater::zlib; }

 private:
  ZlibSource(std::filesystem::path path, gzFile file) : path_(std::move(path)), file_(file) {}
  ZlibSource(const ZlibSource&) = delete;
  ZlibSource& operator=(const ZlibSource&) = delete;

  std::filesystem::path path_;  // zlib's messages start with it
  gzFile file_;
};

#ifdef SSLF_HAVE_ISAL

// What an isal_inflate error means, in zlib's words where zlib has them.
std::string isal_problem(int status) {
  switch (status) {
    case ISAL_INVALID_BLOCK:
      return "invalid deflate block";
    case ISAL_INVALID_SYMBOL:
      return "invalid deflate code";
    case ISAL_INVALID_LOOKBACK:
      return "invalid distance too far back";
    case ISAL_INVALID_WRAPPER:
      return "invalid gzip header";
    case ISAL_UNSUPPORTED_METHOD:
      return "unknown compression method";
    case ISAL_INCORRECT_CHECKSUM:
      return "incorrect data check (CRC-32 or length)";
    default:
      return "ISA-L inflate error " + std::to_string(status);
  }
}

// ISA-L's inflate over a regular gzip file. With ISAL_GZIP, isal_inflate reads each member's
// header and checks its CRC-32 and length; members that follow one another are read one after
// the other, and what follows the last one is ignored, both as zlib does.
class IsalSource final : public CompressedInput::Source {
 public:
  static Result<std::unique_ptr<Source>> open(const std::filesystem::path& path) {
    errno = 0;
    FilePtr file(std::fopen(path.c_str(), "rb"));
    if (!file) return fail(path.string() + ": cannot open: " + std::strerror(errno));
    std::setvbuf(file.get(), nullptr, _IONBF, 0);  // input_ is the buffer
    return std::unique_ptr<Source>(new IsalSource(std::move(file)));
  }

  std::size_t read(char* buffer, std::size_t size) override {
    auto* const out = reinterpret_cast<std::uint8_t*>(buffer);
    std::size_t made = 0;
    while (made < size && !last_member_read_ && fault() == Fault::none) {
      if (state_->block_state == ISAL_BLOCK_FINISH && !start_next_member()) break;
      if (state_->avail_in == 0 && !file_ended_) refill();
      if (fault() != Fault::none) break;  // the file could not be read
      state_->next_out = out + made;
      state_->avail_out = static_cast<std::uint32_t>(std::min(size - made, kLargestRead));
      const int status = isal_inflate(state_.get());
      const auto got = static_cast<std::size_t>(state_->next_out - (out + made));
      made += got;
      if (status < 0) {
        set_fault(Fault::damaged, isal_problem(status));
      } else if (got == 0 && state_->avail_in == 0 && file_ended_ &&
                 state_->block_state != ISAL_BLOCK_FINISH) {
        // Every byte of the file is in and inflating gave nothing more: the member stops early.
        set_fault(Fault::cut_off);
      }
    }
    return made;
  }
  std::uint64_t compressed_offset() const override { return read_from_file_ - state_->avail_in; }
  Inflater inflater() const override { return Inflater::isal; }

 private:
  explicit IsalSource(FilePtr file)
      : file_(std::move(file)),
        input_(std::make_unique<std::uint8_t[]>(kGzipInputSize)),
        state_(std::make_unique<inflate_state>()) {
    isal_inflate_init(state_.get());
    state_->crc_flag = ISAL_GZIP;
    state_->next_in = input_.get();
  }

  // Moves the input not inflated yet to the front and reads more from the file behind it.
  void refill() {
    const std::uint32_t kept = state_->avail_in;
    std::memmove(input_.get(), state_->next_in, kept);
    const std::size_t wanted = kGzipInputSize - kept;
    const std::size_t got = std::fread(input_.get() + kept, 1, wanted, file_.get());
    read_from_file_ += got;
    state_->next_in = input_.get();
    state_->avail_in = kept + static_cast<std::uint32_t>(got);
    if (got < wanted) {
      file_ended_ = true;
      if (std::ferror(file_.get())) set_fault(Fault::damaged, std::strerror(errno));
    }
  }

  // After a member's trailer: another member follows when the next two bytes are gzip's magic.
  bool start_next_member() {
    if (state_->avail_in < 2 && !file_ended_) refill();
    const std::uint8_t* next = state_->next_in;
    if (fault() != Fault::none || state_->avail_in < 2 || next[0] != 0x1f || next[1] != 0x8b) {
      state_->avail_in = 0;  // trailing bytes are skipped, as zlib skips them
      last_member_read_ = true;
      return false;
    }
    isal_inflate_reset(state_.get());  // keeps crc_flag: the new member's header is read too
    return true;
  }

  FilePtr file_;
  std::unique_ptr<std::uint8_t[]> input_;  // compressed bytes read, from state_->next_in on
  std::unique_ptr<inflate_state> state_;   // 85 KiB: on the heap
  std::uint64_t read_from_file_ = 0;
  bool file_ended_ = false;        // the file has no more bytes
  bool last_member_read_ = false;  // the last member is read
};

#endif  // SSLF_HAVE_ISAL

Result<std::unique_ptr<CompressedInput::Source>> open_source(const std::filesystem::path& path,
                                                             [[maybe_unused]] Inflater inflater) {
  const FileKind kind = kind_of(path);
#ifdef SSLF_HAVE_ISAL
  if (kind == FileKind::gzip && inflater != Inflater::zlib) return IsalSource::open(path);
#endif
  return ZlibSource::open(path, kind);
}

}  // namespace

bool isal_available() {
#ifdef SSLF_HAVE_ISAL
  return true;
#else
  return false;
#endif
}

Result<CompressedInput> CompressedInput::open(const std::filesystem::path& path,
                                              Inflater inflater) {
  if (inflater == Inflater::isal && !isal_available()) {
    return fail(path.string() + ": cannot inflate with ISA-L: this build has none (SSLF_ISAL)");
  }
  Result<std::unique_ptr<Source>> source = open_source(path, inflater);
  if (!source) return Unexpected(std::move(source).error());
  CompressedInput input(std::move(*source));
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  input.compressed_size_ = ec ? 0 : static_cast<std::uint64_t>(size);
  return input;
}

CompressedInput::CompressedInput(std::unique_ptr<Source> source) : source_(std::move(source)) {}
CompressedInput::CompressedInput(CompressedInput&&) noexcept = default;
CompressedInput& CompressedInput::operator=(CompressedInput&&) noexcept = default;
CompressedInput::~CompressedInput() = default;

std::size_t CompressedInput::read(char* buffer, std::size_t size) {
  return source_ && size > 0 ? source_->read(buffer, size) : 0;
}

CompressedInput::Fault CompressedInput::fault() const {
  return source_ ? source_->fault() : Fault::none;
}

const std::string& CompressedInput::fault_message() const {
  static const std::string none;
  return source_ ? source_->fault_message() : none;
}

std::uint64_t CompressedInput::compressed_offset() const {
  return source_ ? source_->compressed_offset() : 0;
}

Inflater CompressedInput::inflater() const {
  return source_ ? source_->inflater() : Inflater::zlib;
}

}  // namespace files
}  // namespace ssl_formation
