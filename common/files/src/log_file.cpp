#include "ssl_formation/files/log_file.hpp"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <span>
#include <utility>

#include "ssl_formation/files/replacing_file.hpp"
#include "zlib_errors.hpp"

namespace ssl_formation {
inline namespace files {

namespace {

// Big enough that a whole vision packet (a few hundred bytes, geometry a few KiB) is nearly
// always contiguous in it, so the payload is parsed in place; fill()'s reads into it are mostly
// large enough to skip the input's own buffer.
constexpr std::size_t kReadBufferSize = 256 * 1024;
static_assert(kReadBufferSize >= 4 * CompressedInput::kDirectReadSize);
// The writer's zlib buffer.
constexpr unsigned kGzBufferSize = 128 * 1024;

std::int64_t load_be64(const char* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  return static_cast<std::int64_t>(v);
}

std::int32_t load_be32(const char* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  return static_cast<std::int32_t>(v);
}

void store_be64(char* p, std::int64_t value) {
  const auto v = static_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i) p[i] = static_cast<char>((v >> (56 - 8 * i)) & 0xff);
}

void store_be32(char* p, std::int32_t value) {
  const auto v = static_cast<std::uint32_t>(value);
  for (int i = 0; i < 4; ++i) p[i] = static_cast<char>((v >> (24 - 8 * i)) & 0xff);
}

bool ends_with_gz(const std::filesystem::path& path) {
  const std::string name = path.filename().string();
  return name.size() >= 3 && name.compare(name.size() - 3, 3, ".gz") == 0;
}

// A type-2 packet decoded with today's schema is usable when the detection fields that mean the
// same in the 2010 schema are there. The 2010 geometry used other field numbers (field 1 was the
// line width), so it is dropped rather than misread. Required fields nobody downstream needs are
// given neutral values, so the packet is initialized and can be written or sent again.
bool adopt_legacy(SSL_WrapperPacket& packet) {
  if (!packet.has_detection()) return false;
  SSL_DetectionFrame& frame = *packet.mutable_detection();
  if (!frame.has_frame_number() || !frame.has_t_capture() || !frame.has_camera_id()) return false;
  for (const auto& ball : frame.balls())
    if (!ball.has_x() || !ball.has_y()) return false;
  for (const auto* robots : {&frame.robots_yellow(), &frame.robots_blue()})
    for (const auto& robot : *robots)
      if (!robot.has_x() || !robot.has_y()) return false;
  packet.clear_geometry();
  if (!frame.has_t_sent()) frame.set_t_sent(frame.t_capture());
  for (auto& ball : *frame.mutable_balls()) {
    if (!ball.has_confidence()) ball.set_confidence(1.0f);
    if (!ball.has_pixel_x()) ball.set_pixel_x(0.0f);
    if (!ball.has_pixel_y()) ball.set_pixel_y(0.0f);
  }
  for (auto* robots : {frame.mutable_robots_yellow(), frame.mutable_robots_blue()})
    for (auto& robot : *robots) {
      if (!robot.has_confidence()) robot.set_confidence(1.0f);
      if (!robot.has_pixel_x()) robot.set_pixel_x(0.0f);
      if (!robot.has_pixel_y()) robot.set_pixel_y(0.0f);
    }
  return true;
}

}  // namespace

namespace detail {
void GzFileCloser::operator()(gzFile_s* file) const noexcept {
  if (file != nullptr) gzclose(file);
}
}  // namespace detail

// ---------------------------------------------------------------------------------------------
// LogReader

LogReader::LogReader(std::filesystem::path path, CompressedInput input)
    : path_(std::move(path)),
      input_(std::move(input)),
      buffer_(std::make_unique<char[]>(kReadBufferSize)) {}

Result<LogReader> LogReader::open(const std::filesystem::path& path, Inflater inflater) {
  const auto failure = [&](const std::string& message) {
    return ssl_formation::fail(path.string() + ": " + message);
  };
  Result<CompressedInput> input = CompressedInput::open(path, inflater);
  if (!input) return Unexpected(std::move(input).error());
  LogReader reader(path, std::move(*input));

  reader.fill(kLogFileHeaderSize);
  if (reader.input_.fault() == CompressedInput::Fault::damaged) {
    return failure("cannot read: " + reader.input_.fault_message());
  }
  const char* data = reader.buffer_.get() + reader.begin_;
  if (reader.available() == 0) return failure("not an SSL log file (empty)");
  if (reader.available() < kLogFileMagic.size() ||
      std::string_view(data, kLogFileMagic.size()) != kLogFileMagic) {
    return failure("not an SSL log file (bad header at byte 0)");
  }
  if (reader.available() < kLogFileHeaderSize) {
    return failure("truncated header at byte " + std::to_string(kLogFileMagic.size()) +
                   ": the version needs 4 bytes, " +
                   std::to_string(reader.available() - kLogFileMagic.size()) + " remain");
  }
  const std::int32_t version = load_be32(data + kLogFileMagic.size());
  if (version != kLogFileVersion) {
    return failure("unsupported log version " + std::to_string(version) + " at byte " +
                   std::to_string(kLogFileMagic.size()));
  }
  reader.consume(kLogFileHeaderSize);
  reader.counters_.bytes = reader.offset_;
  return reader;
}

void LogReader::consume(std::size_t n) {
  begin_ += n;
  offset_ += n;
}

bool LogReader::fill(std::size_t n) {
  if (available() >= n) return true;
  if (begin_ > 0) {
    std::memmove(buffer_.get(), buffer_.get() + begin_, available());
    end_ -= begin_;
    begin_ = 0;
  }
  while (end_ < n && !eof_) {
    const std::size_t got = input_.read(buffer_.get() + end_, kReadBufferSize - end_);
    if (got == 0) {
      eof_ = true;  // a fault is reported by input_problem()
      break;
    }
    end_ += got;
  }
  return available() >= n;
}

std::size_t LogReader::read_large(std::size_t size) {
  scratch_.resize(size);
  std::size_t got = std::min(size, available());
  std::memcpy(scratch_.data(), buffer_.get() + begin_, got);
  consume(got);
  while (got < size && !eof_) {
    const std::size_t n = input_.read(scratch_.data() + got, size - got);
    if (n == 0) {
      eof_ = true;
      break;
    }
    got += n;
    offset_ += n;
  }
  return got;
}

std::string LogReader::input_problem() const {
  switch (input_.fault()) {
    case CompressedInput::Fault::none:
      return {};
    case CompressedInput::Fault::cut_off:
      return " (the gzip stream is cut off)";
    case CompressedInput::Fault::damaged:
      break;
  }
  return " (gzip: " + input_.fault_message() + ")";
}

LogReader::Ending LogReader::cut_off_ending() const {
  // The bytes simply stop (a plain file, or a gzip stream cut off): a cut-off last message.
  // Any other fault is damage inside the stream or a failed read.
  return input_.fault() == CompressedInput::Fault::damaged ? Ending::damaged : Ending::cut_off;
}

bool LogReader::fail(std::string message, Ending ending) {
  error_ = path_.string() + ": " + std::move(message);
  ending_ = ending;
  done_ = true;
  return false;
}

void LogReader::count(std::int32_t type) {
  ++counters_.messages;
  switch (static_cast<LogMessageType>(type)) {
    case LogMessageType::blank:
      ++counters_.blank;
      break;
    case LogMessageType::legacy_vision:
      ++counters_.legacy_vision;
      break;
    case LogMessageType::referee:
      ++counters_.referee;
      break;
    case LogMessageType::vision:
      ++counters_.vision;
      break;
    case LogMessageType::tracker:
      ++counters_.tracker;
      break;
    case LogMessageType::index:
      ++counters_.index;
      break;
    case LogMessageType::unknown:
    default:
      ++counters_.unknown;
      break;
  }
}

bool LogReader::next_view(Header& header, std::string_view& payload) {
  if (done_ || !buffer_) return false;  // no buffer: moved from
  const std::uint64_t at = offset_;
  if (!fill(kLogMessageHeaderSize)) {
    const std::string problem = input_problem();
    if (available() == 0 && problem.empty()) {
      done_ = true;  // clean end
      return false;
    }
    if (available() == 0) {
      return fail("read failed at byte " + std::to_string(at) + problem, cut_off_ending());
    }
    return fail("truncated message header at byte " + std::to_string(at) + ": " +
                    std::to_string(kLogMessageHeaderSize) + " bytes needed, " +
                    std::to_string(available()) + " remain" + problem,
                cut_off_ending());
  }
  const char* data = buffer_.get() + begin_;
  header.receive_time_ns = load_be64(data);
  header.type = load_be32(data + 8);
  header.size = load_be32(data + 12);
  header.offset = at;
  if (header.type == static_cast<std::int32_t>(LogMessageType::index)) {
    // The index closes an indexed file; what follows it is the index itself and its trailer,
    // which a sequential reader has no use for (and which may exceed the size limit below).
    count(header.type);
    done_ = true;
    return false;
  }
  if (header.size < 0 || header.size > kLogMaxMessageSize) {
    return fail("absurd message size " + std::to_string(header.size) + " at byte " +
                std::to_string(at));
  }
  const auto size = static_cast<std::size_t>(header.size);
  if (kLogMessageHeaderSize + size <= kReadBufferSize) {
    if (!fill(kLogMessageHeaderSize + size)) {
      return fail("truncated message at byte " + std::to_string(at) + ": header says " +
                      std::to_string(size) + " bytes, " +
                      std::to_string(available() - kLogMessageHeaderSize) + " remain" +
                      input_problem(),
                  cut_off_ending());
    }
    payload = std::string_view(buffer_.get() + begin_ + kLogMessageHeaderSize, size);
    consume(kLogMessageHeaderSize + size);
  } else {
    consume(kLogMessageHeaderSize);
    const std::size_t got = read_large(size);
    if (got < size) {
      return fail("truncated message at byte " + std::to_string(at) + ": header says " +
                      std::to_string(size) + " bytes, " + std::to_string(got) + " remain" +
                      input_problem(),
                  cut_off_ending());
    }
    payload = scratch_;
  }
  counters_.bytes = offset_;
  count(header.type);
  return true;
}

bool LogReader::next(LogMessage& out) {
  Header header{};
  std::string_view payload;
  if (!next_view(header, payload)) return false;
  out.receive_time_ns = header.receive_time_ns;
  out.type = header.type;
  out.payload.assign(payload.data(), payload.size());  // reuses out.payload's capacity
  out.offset = header.offset;
  return true;
}

bool LogReader::parse_vision(const Header& header, std::string_view payload,
                             SSL_WrapperPacket& packet) {
  const int size = static_cast<int>(payload.size());
  if (header.type == static_cast<std::int32_t>(LogMessageType::vision)) {
    if (packet.ParseFromArray(payload.data(), size)) return true;
    ++counters_.parse_errors;
  } else if (header.type == static_cast<std::int32_t>(LogMessageType::legacy_vision)) {
    if (!packet.ParsePartialFromArray(payload.data(), size)) {
      ++counters_.parse_errors;
    } else if (adopt_legacy(packet)) {
      return true;
    } else {
      ++counters_.legacy_unusable;
    }
  }
  return false;
}

bool LogReader::next_vision(SSL_WrapperPacket& packet, std::int64_t* receive_time_ns) {
  Header header{};
  std::string_view payload;
  while (next_view(header, payload)) {
    if (parse_vision(header, payload, packet)) {
      if (receive_time_ns != nullptr) *receive_time_ns = header.receive_time_ns;
      return true;
    }
  }
  return false;
}

bool LogReader::decode_vision(const Header& header, std::string_view payload, VisionFrame& frame) {
  // The fast path takes only what protobuf would accept and convert to the same frame; the 2010
  // schema (type 2) always goes through protobuf and adopt_legacy.
  if (header.type == static_cast<std::int32_t>(LogMessageType::vision) &&
      decode_detection_datagram(std::as_bytes(std::span(payload)), frame)) {
    return true;
  }
  if (!parse_vision(header, payload, packet_scratch_)) return false;
  to_vision_frame(packet_scratch_, frame);
  return true;
}

bool LogReader::next_vision(VisionFrame& frame, std::int64_t* receive_time_ns) {
  Header header{};
  std::string_view payload;
  while (next_view(header, payload)) {
    if (decode_vision(header, payload, frame)) {
      if (receive_time_ns != nullptr) *receive_time_ns = header.receive_time_ns;
      return true;
    }
  }
  return false;
}

template <class Decode>
bool LogReader::next_match_message(MatchInput& kind, std::string_view& payload,
                                   std::int64_t* receive_time_ns, Decode decode) {
  Header header{};
  std::string_view bytes;
  while (next_view(header, bytes)) {
    if (header.type == static_cast<std::int32_t>(LogMessageType::referee)) {
      kind = MatchInput::referee;
      payload = bytes;
    } else if (header.type == static_cast<std::int32_t>(LogMessageType::tracker)) {
      kind = MatchInput::tracker;
      payload = bytes;
    } else if (decode(header, bytes)) {
      kind = MatchInput::vision;
    } else {
      continue;
    }
    if (receive_time_ns != nullptr) *receive_time_ns = header.receive_time_ns;
    return true;
  }
  return false;
}

bool LogReader::next_match_input(MatchInput& kind, VisionFrame& frame, std::string_view& payload,
                                 std::int64_t* receive_time_ns) {
  return next_match_message(kind, payload, receive_time_ns,
                            [&](const Header& header, std::string_view bytes) {
                              return decode_vision(header, bytes, frame);
                            });
}

bool LogReader::next_match_input(MatchInput& kind, SSL_WrapperPacket& packet,
                                 std::string_view& payload, std::int64_t* receive_time_ns) {
  return next_match_message(kind, payload, receive_time_ns,
                            [&](const Header& header, std::string_view bytes) {
                              return parse_vision(header, bytes, packet);
                            });
}

// ---------------------------------------------------------------------------------------------
// LogWriter

void LogWriter::Temporary::remove() noexcept {
  if (path.empty()) return;
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
  path.clear();
}

LogWriter::LogWriter(std::filesystem::path path, Temporary temporary, detail::GzFilePtr file)
    : path_(std::move(path)), temporary_(std::move(temporary)), file_(std::move(file)) {}

Result<LogWriter> LogWriter::create(const std::filesystem::path& path) {
  errno = 0;
  // A device or a pipe (/dev/null) is written to as it is.
  const bool in_place = written_in_place(path);
  Temporary temporary(in_place ? std::filesystem::path() : temporary_beside(path));
  // "T": zlib writes the bytes through uncompressed, so both kinds share one code path.
  gzFile file =
      gzopen((in_place ? path : temporary.path).c_str(), ends_with_gz(path) ? "wb6" : "wbT");
  if (file == nullptr) {
    temporary.path.clear();  // nothing was created
    return fail(path.string() + ": cannot create: " + detail::zlib_errno_text(errno));
  }
  gzbuffer(file, kGzBufferSize);
  LogWriter writer(path, std::move(temporary), detail::GzFilePtr(file));
  char header[kLogFileHeaderSize];
  std::memcpy(header, kLogFileMagic.data(), kLogFileMagic.size());
  store_be32(header + kLogFileMagic.size(), kLogFileVersion);
  if (!writer.put(header, sizeof header)) return fail(writer.error_);
  return writer;
}

bool LogWriter::put(const void* data, std::size_t size) {
  if (size == 0) return true;  // gzwrite returns 0 for 0 bytes, which reads as an error
  const int written = gzwrite(file_.get(), data, static_cast<unsigned>(size));
  if (written != static_cast<int>(size)) {
    int code = Z_OK;
    const char* message = gzerror(file_.get(), &code);
    error_ =
        path_.string() + ": cannot write at byte " + std::to_string(offset_) + ": " +
        (code == Z_ERRNO ? detail::zlib_errno_text(errno) : detail::without_path(message, path_));
    failed_ = true;
    return false;
  }
  offset_ += size;
  return true;
}

bool LogWriter::put_message(std::int32_t type, std::int64_t receive_time_ns,
                            std::string_view payload) {
  char header[kLogMessageHeaderSize];
  store_be64(header, receive_time_ns);
  store_be32(header + 8, type);
  store_be32(header + 12, static_cast<std::int32_t>(payload.size()));
  const auto at = static_cast<std::int64_t>(offset_);
  if (!put(header, sizeof header) || !put(payload.data(), payload.size())) return false;
  message_offsets_.push_back(at);
  last_time_ns_ = receive_time_ns;
  return true;
}

bool LogWriter::write(std::int32_t type, std::int64_t receive_time_ns, std::string_view payload) {
  if (!file_) {
    error_ = path_.string() + ": already closed";
    return false;
  }
  if (failed_) return false;
  if (type == static_cast<std::int32_t>(LogMessageType::index)) {
    // Readers stop at an index message, so one in the middle would hide the rest of the log.
    error_ = path_.string() + ": index messages are written by close(true), not write()";
    return false;
  }
  if (payload.size() > static_cast<std::size_t>(kLogMaxMessageSize)) {
    error_ = path_.string() + ": message of " + std::to_string(payload.size()) + " bytes at byte " +
             std::to_string(offset_) + " exceeds the " + std::to_string(kLogMaxMessageSize) +
             "-byte limit readers accept";
    return false;
  }
  return put_message(type, receive_time_ns, payload);
}

bool LogWriter::write_vision(const SSL_WrapperPacket& packet, std::int64_t receive_time_ns) {
  if (!packet.IsInitialized()) {
    error_ = path_.string() +
             ": vision packet lacks required fields: " + packet.InitializationErrorString();
    return false;
  }
  packet.SerializeToString(&scratch_);  // reuses scratch_'s capacity
  return write(static_cast<std::int32_t>(LogMessageType::vision), receive_time_ns, scratch_);
}

bool LogWriter::close(bool indexed) {
  if (!file_) {
    error_ = path_.string() + ": already closed";
    return false;
  }
  bool ok = !failed_;
  if (ok && indexed) {
    // As ssl-go-tools writes it: the index message's payload is every message's offset, then
    // the distance from the end of the file back to the index message, then "INDEXED".
    const std::size_t trailer = 8 + kLogIndexMarker.size();
    std::string payload(message_offsets_.size() * 8 + trailer, '\0');
    char* p = payload.data();
    for (const std::int64_t at : message_offsets_) {
      store_be64(p, at);
      p += 8;
    }
    store_be64(p, static_cast<std::int64_t>(kLogMessageHeaderSize + payload.size()));
    std::memcpy(p + 8, kLogIndexMarker.data(), kLogIndexMarker.size());
    ok = put_message(static_cast<std::int32_t>(LogMessageType::index), last_time_ns_, payload);
  }
  errno = 0;
  const int result = gzclose(file_.release());
  if (ok && result != Z_OK) {
    error_ = path_.string() + ": cannot finish writing: " +
             (result == Z_ERRNO ? detail::zlib_errno_text(errno) : std::string(zError(result)));
    ok = false;
  }
  if (ok && !temporary_.path.empty()) {
    std::error_code error;
    std::filesystem::rename(temporary_.path, path_, error);
    if (error) {
      error_ = path_.string() + ": cannot replace: " + error.message();
      ok = false;
    } else {
      temporary_.path.clear();
    }
  }
  temporary_.remove();  // a log that failed leaves the path as it was
  failed_ = failed_ || !ok;
  return ok;
}

// ---------------------------------------------------------------------------------------------

Result<LogVisionPackets> read_vision_log(const std::filesystem::path& path) {
  Result<LogReader> reader = LogReader::open(path);
  if (!reader) return Unexpected(std::move(reader).error());
  LogVisionPackets out;
  SSL_WrapperPacket packet;
  std::int64_t receive_time_ns = 0;
  while (reader->next_vision(packet, &receive_time_ns)) {
    out.packets.push_back(std::move(packet));
    out.receive_times_ns.push_back(receive_time_ns);
    packet.Clear();
  }
  if (reader->ending() != LogReader::Ending::none) out.stopped_early = Error{reader->error()};
  out.ending = reader->ending();
  out.counters = reader->counters();
  return out;
}

}  // namespace files
}  // namespace ssl_formation
