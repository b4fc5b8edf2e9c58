#pragma once
// The official SSL log file: "SSL_LOG_FILE", a big-endian int32 version (1), then
// messages of big-endian int64 receive time (ns), int32 type, int32 size and size payload bytes.
// `.log.gz` is the same stream gzip-compressed; the reader takes either, whatever the name.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ssl_formation/base/result.hpp"
#include "ssl_formation/files/compressed_input.hpp"
#include "ssl_formation/vision/vision_frame.hpp"
#include "ssl_vision_wrapper.pb.h"

struct gzFile_s;  // zlib's file (the writer's), kept out of this header

namespace ssl_formation {
inline namespace files {

enum class LogMessageType : std::int32_t {
  blank = 0,
  unknown = 1,
  legacy_vision = 2,  // SSL_WrapperPacket of the 2010 schema
  referee = 3,
  vision = 4,  // SSL_WrapperPacket
  tracker = 5,
  // Last message of an indexed file (ssl-go-tools): its payload is every message's int64
  // offset, then the int64 distance from the end of the file back to it, then "INDEXED".
  index = 6,
};

inline constexpr std::string_view kLogFileMagic = "SSL_LOG_FILE";
inline constexpr std::int32_t kLogFileVersion = 1;
inline constexpr std::size_t kLogFileHeaderSize = 16;     // magic + version
inline constexpr std::size_t kLogMessageHeaderSize = 16;  // time + type + size
inline constexpr std::string_view kLogIndexMarker = "INDEXED";
// Larger sizes (and negative ones) are taken as corruption: no real message comes near it.
inline constexpr std::int64_t kLogMaxMessageSize = 16 * 1024 * 1024;

struct LogMessage {
  std::int64_t receive_time_ns = 0;
  std::int32_t type = 0;
  std::string payload;
  std::uint64_t offset = 0;  // of the message header in the uncompressed stream
};

// What a reader has seen so far. Every message counts once in `messages` and once by type.
struct LogReadCounters {
  std::uint64_t messages = 0;
  std::uint64_t vision = 0;         // type 4
  std::uint64_t legacy_vision = 0;  // type 2
  std::uint64_t referee = 0;        // type 3
  std::uint64_t tracker = 0;        // type 5
  std::uint64_t index = 0;          // type 6
  std::uint64_t unknown = 0;        // type 1 and types outside 0-6
  std::uint64_t parse_errors = 0;   // type 4 or 2 payloads that did not decode (next_vision only)
  std::uint64_t bytes = 0;          // uncompressed bytes consumed, file header included
  std::uint64_t blank = 0;          // type 0
  // Type 2 packets that decoded but lack a usable detection frame (next_vision only).
  std::uint64_t legacy_unusable = 0;
};

namespace detail {
struct GzFileCloser {
  // gzclose reports nothing a destructor could act on: LogWriter::close() is where the errors of
  // closing a written file are reported.
  void operator()(gzFile_s* file) const noexcept;
};
using GzFilePtr = std::unique_ptr<gzFile_s, GzFileCloser>;
}  // namespace detail

// Reads messages one by one through a buffer, reusing its storage: no allocation per message.
class LogReader {
 public:
  // Opens and checks the header; on failure the error names the path and the problem. The
  // inflater is for tests and benchmarks that compare zlib's with ISA-L's (compressed_input.hpp).
  static Result<LogReader> open(const std::filesystem::path& path,
                                Inflater inflater = Inflater::automatic);

  // Next raw message; false at the end of the file or on an error. An index message ends the
  // file: it is counted but not read or returned (a long log's index may exceed the size limit).
  // error() is empty after a clean end, else it names the byte offset of the bad message header.
  bool next(LogMessage& out);
  // Next vision packet (type 4, and type 2 when its detection frame is usable; the 2010 geometry
  // is dropped since its field numbers mean other things now), skipping and counting the others.
  // Packets that fail to parse are counted as parse_errors and skipped.
  bool next_vision(SSL_WrapperPacket& packet, std::int64_t* receive_time_ns = nullptr);
  // The same packets as what sampling reads (VisionFrame), skipped and counted alike: each frame
  // is to_vision_frame() of the packet the overload above returns. A detection-only type-4
  // payload is decoded straight from the bytes (decode_detection_datagram), anything else is
  // parsed by protobuf as above; offline training's protobuf parse was most of its reading time.
  bool next_vision(VisionFrame& frame, std::int64_t* receive_time_ns = nullptr);
  // What the match is followed by, in the file's order: the vision frames next_vision() returns
  // (kind vision, into `frame`), the referee messages (type 3) and the trackers' packets (type
  // 5), these two as their payload viewed in `payload` (valid until the next call). Everything
  // else is skipped and counted.
  enum class MatchInput { vision, referee, tracker };
  bool next_match_input(MatchInput& kind, VisionFrame& frame, std::string_view& payload,
                        std::int64_t* receive_time_ns = nullptr);
  // The same with the vision packets as next_vision(SSL_WrapperPacket&) returns them (a replay
  // sends them on as they are).
  bool next_match_input(MatchInput& kind, SSL_WrapperPacket& packet, std::string_view& payload,
                        std::int64_t* receive_time_ns = nullptr);

  const std::string& error() const { return error_; }
  // How reading ended so far: the file ending inside its last message (what a recorder killed
  // mid-write leaves: everything before it is whole) is told apart from damage (an absurd size,
  // corrupt gzip data, a failed read), after which nothing more could be trusted.
  enum class Ending { none, cut_off, damaged };
  Ending ending() const { return ending_; }
  const LogReadCounters& counters() const { return counters_; }
  const std::filesystem::path& path() const { return path_; }
  std::uint64_t offset() const { return offset_; }  // bytes consumed so far (uncompressed)
  std::uint64_t compressed_size() const { return input_.compressed_size(); }  // the file on disk
  // How far into the file on disk, for progress bars.
  std::uint64_t compressed_offset() const { return input_.compressed_offset(); }
  Inflater inflater() const { return input_.inflater(); }  // zlib or isal: what reads the file

 private:
  struct Header {
    std::int64_t receive_time_ns;
    std::int32_t type;
    std::int32_t size;
    std::uint64_t offset;
  };

  explicit LogReader(std::filesystem::path path, CompressedInput input);
  // Parses a vision payload (type 4, or a usable type 2) into `packet`, counting what fails.
  bool parse_vision(const Header& header, std::string_view payload, SSL_WrapperPacket& packet);
  // The same into a frame, decoding a detection-only type-4 payload straight from its bytes.
  bool decode_vision(const Header& header, std::string_view payload, VisionFrame& frame);
  // next_match_input() with `decode(header, bytes)` deciding whether a message is usable vision.
  template <class Decode>
  bool next_match_message(MatchInput& kind, std::string_view& payload,
                          std::int64_t* receive_time_ns, Decode decode);
  // The next message's header and payload; the payload view stays valid until the next call.
  bool next_view(Header& header, std::string_view& payload);
  void count(std::int32_t type);
  // Makes at least n buffered bytes available if the file has them; false if not.
  bool fill(std::size_t n);
  std::size_t available() const { return end_ - begin_; }
  void consume(std::size_t n);
  // Fills `scratch_` with a payload too large for the buffer; returns the bytes got.
  std::size_t read_large(std::size_t size);
  bool fail(std::string message, Ending ending = Ending::damaged);
  // The input's fault after a short read (corrupt or cut-off gzip data), or empty.
  std::string input_problem() const;
  // cut_off when the file (or its gzip stream) just stops, damaged for corrupt gzip data or a
  // failed read.
  Ending cut_off_ending() const;

  std::filesystem::path path_;
  CompressedInput input_;
  std::unique_ptr<char[]> buffer_;
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
  bool eof_ = false;   // the file has no more bytes
  bool done_ = false;  // clean end or error: next() returns false from now on
  std::string scratch_;
  SSL_WrapperPacket packet_scratch_;  // next_vision(VisionFrame&)'s protobuf parses
  std::string error_;
  Ending ending_ = Ending::none;
  LogReadCounters counters_;
  std::uint64_t offset_ = 0;
};

// Writes a log, gzip-compressed when the path ends in ".gz". Failed writes are sticky. The log is
// written to a temporary file beside the path and takes the path's place only when close()
// succeeds: a writer that fails or is never closed leaves an earlier file there as it was.
class LogWriter {
 public:
  // Creates the temporary file and writes the header; the error names the path and cause.
  static Result<LogWriter> create(const std::filesystem::path& path);

  // Refuses (false, error()) payloads over kLogMaxMessageSize, which no reader would accept.
  bool write(std::int32_t type, std::int64_t receive_time_ns, std::string_view payload);
  bool write_vision(const SSL_WrapperPacket& packet, std::int64_t receive_time_ns);
  // indexed: append an index message (payload: the big-endian int64 offset of every message
  // header), its own offset as int64 and "INDEXED". false + error() on any failure. The
  // file then replaces the path. The destructor of an unclosed writer removes what it wrote.
  bool close(bool indexed = false);

  const std::string& error() const { return error_; }
  std::uint64_t offset() const { return offset_; }  // uncompressed bytes written so far

 private:
  // The temporary file until close() renames it: removed with the writer otherwise.
  struct Temporary {
    std::filesystem::path path;
    Temporary() = default;
    explicit Temporary(std::filesystem::path p) : path(std::move(p)) {}
    Temporary(Temporary&& other) noexcept : path(std::exchange(other.path, {})) {}
    Temporary& operator=(Temporary&& other) noexcept {
      if (this != &other) {
        remove();
        path = std::exchange(other.path, {});
      }
      return *this;
    }
    ~Temporary() { remove(); }
    void remove() noexcept;
  };
  LogWriter(std::filesystem::path path, Temporary temporary, detail::GzFilePtr file);
  bool put(const void* data, std::size_t size);
  bool put_message(std::int32_t type, std::int64_t receive_time_ns, std::string_view payload);

  std::filesystem::path path_;
  Temporary temporary_;
  detail::GzFilePtr file_;  // closed before temporary_ goes
  std::string error_;
  std::uint64_t offset_ = 0;
  std::int64_t last_time_ns_ = 0;
  std::vector<std::int64_t> message_offsets_;
  std::string scratch_;
  bool failed_ = false;
};

// A whole file's vision packets and the counters. A file that stops early (cut off in its last
// message, or damaged) still gives every packet before the damage: `packets` holds them, and
// `stopped_early` says where and why reading stopped (LogReader::error()), `ending` how.
struct LogVisionPackets {
  std::vector<SSL_WrapperPacket> packets;
  std::vector<std::int64_t> receive_times_ns;
  std::optional<Error> stopped_early;  // nullopt when the file was read to its end
  LogReader::Ending ending = LogReader::Ending::none;
  LogReadCounters counters;
};

// An error only when the file cannot be opened or has no valid header (LogReader::open's error);
// damage after the header is reported in the packets' `stopped_early`.
Result<LogVisionPackets> read_vision_log(const std::filesystem::path& path);

}  // namespace files
}  // namespace ssl_formation
