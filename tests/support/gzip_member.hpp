#pragma once
// One gzip member, made by zlib's deflate in memory: test input for the readers that is made
// independently of the log writer under test. Concatenated members make a multi-member file, as
// `cat a.gz b.gz` does.

#include <gtest/gtest.h>
#include <zlib.h>

#include <string>

namespace ssl_formation::testing {

// `name`, when given, goes into the header as gzip(1) puts the file's name there.
inline std::string gzip_member(const std::string& data, int level = Z_DEFAULT_COMPRESSION,
                               const char* name = nullptr) {
  z_stream stream{};
  EXPECT_EQ(deflateInit2(&stream, level, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
  gz_header header{};
  std::string name_storage = name != nullptr ? name : "";
  if (name != nullptr) {
    header.name = reinterpret_cast<Bytef*>(name_storage.data());
    EXPECT_EQ(deflateSetHeader(&stream, &header), Z_OK);
  }
  std::string out(deflateBound(&stream, data.size()) + 64, '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  stream.avail_in = static_cast<uInt>(data.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&stream, Z_FINISH), Z_STREAM_END);
  out.resize(stream.total_out);
  deflateEnd(&stream);
  return out;
}

}  // namespace ssl_formation::testing
