#pragma once
// The motion section of a table file built field by field from the layouts table_file.hpp
// documents, independently of the product's writer: the tests make older versions' files (3
// and 4, which the product reads but no longer writes) and plant inconsistent content in the
// compact version 5 under valid checksums.
#include <bit>
#include <cstdint>
#include <utility>
#include <vector>

#include "ssl_formation/motion_model/motion_model.hpp"
#include "table_bytes.hpp"

namespace ssl_formation::testing {

// What a motion section says, field by field.
struct MotionSectionContent {
  MotionConfig config;
  std::uint64_t instances = 0;
  std::uint64_t held_out_seen = 0;
  std::uint64_t row_count = 0;  // as stated: tests may make it disagree with `rows`
  std::vector<std::pair<MotionKey, MotionRow>> rows;
  std::vector<std::vector<HeldOutInstance>> samples;  // per horizon
  std::vector<SetPlayEpisode> kickoffs;

  static MotionSectionContent of(const MotionTable& table) {
    MotionSectionContent c;
    c.config = table.config();
    c.instances = table.instances();
    c.held_out_seen = table.held_out();
    c.rows = table.sorted_rows();
    c.row_count = c.rows.size();
    for (int h = 0; h < c.config.horizons; ++h) c.samples.push_back(table.calibration(h));
    c.kickoffs = table.set_plays().episodes();
    return c;
  }
};

class SectionWriter {
 public:
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void varint(std::uint64_t v) {
    for (; v >= 0x80; v >>= 7) bytes.push_back(static_cast<std::uint8_t>(v | 0x80));
    bytes.push_back(static_cast<std::uint8_t>(v));
  }
  void zigzag(std::int64_t v) {
    varint((static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63));
  }
  void append(const Bytes& more) { bytes.insert(bytes.end(), more.begin(), more.end()); }
  Bytes bytes;
};

inline void write_config_and_counts(SectionWriter& w, const MotionSectionContent& c) {
  const MotionConfig& k = c.config;
  w.f64(k.step_s);
  w.u32(static_cast<std::uint32_t>(k.horizons));
  w.f64(k.velocity_window_s);
  w.f64(k.tolerance_s);
  w.f64(k.calibration_block_s);
  w.u32(k.calibration_one_in);
  w.u32(k.calibration_capacity);
  w.f64(k.settle_window_s);
  w.f64(k.long_settle_window_s);
  w.f64(k.learn_interval_s);
  w.u64(c.instances);
  w.u64(c.held_out_seen);
  w.u64(c.row_count);
}

inline void write_kickoffs(SectionWriter& w, const MotionSectionContent& c) {
  w.u32(static_cast<std::uint32_t>(c.kickoffs.size()));
  for (const SetPlayEpisode& episode : c.kickoffs) {
    w.u32(static_cast<std::uint32_t>(episode.snapshots.size()));
    for (const SetPlaySnapshot& s : episode.snapshots) {
      w.u32(static_cast<std::uint32_t>(s.offset_ms));
      w.u32(static_cast<std::uint32_t>(s.since_command_ms));
      w.u32(static_cast<std::uint32_t>(s.stage));
      w.u32(s.seen);
      for (const auto& p : s.position) {
        w.u32(static_cast<std::uint32_t>(p[0]));
        w.u32(static_cast<std::uint32_t>(p[1]));
      }
    }
  }
}

// Versions 3 and 4 (`with_kickoffs`): fixed-width rows and instances.
inline Bytes fixed_motion_section(const MotionSectionContent& c, bool with_kickoffs) {
  SectionWriter w;
  write_config_and_counts(w, c);
  for (const auto& [key, row] : c.rows) {
    w.u64(key);
    for (const std::int64_t sum : row.sums) w.u64(static_cast<std::uint64_t>(sum));
  }
  for (const auto& sample : c.samples) {
    w.u32(static_cast<std::uint32_t>(sample.size()));
    for (const HeldOutInstance& held : sample) {
      w.u64(held.hash);
      w.u32(held.instance.robot_id);
      for (const auto value : motion_instance_values) {
        w.u32(static_cast<std::uint32_t>(held.instance.*value));
      }
      w.u32(held.instance.context);
    }
  }
  if (with_kickoffs) write_kickoffs(w, c);
  return w.bytes;
}

// Version 5: the rows and the instances as varints, each block after its length.
inline Bytes compact_motion_section(const MotionSectionContent& c) {
  SectionWriter rows;
  MotionKey previous = 0;
  for (const auto& [key, row] : c.rows) {
    rows.varint(key - previous);  // wraps for rows out of order, as a writer's bug would
    previous = key;
    for (const std::int64_t sum : row.sums) rows.zigzag(sum);
  }
  SectionWriter samples;
  for (const auto& sample : c.samples) {
    samples.varint(sample.size());
    for (const HeldOutInstance& held : sample) {
      samples.u64(held.hash);
      samples.varint(held.instance.robot_id);
      for (const auto value : motion_instance_values) samples.zigzag(held.instance.*value);
      samples.varint(held.instance.context);
    }
  }
  SectionWriter w;
  write_config_and_counts(w, c);
  w.u64(rows.bytes.size());
  w.append(rows.bytes);
  w.u64(samples.bytes.size());
  w.append(samples.bytes);
  write_kickoffs(w, c);
  return w.bytes;
}

// A version-1 file's bytes (the paper's counts) made a file of `version` with `section`, both
// checksums recomputed.
inline Bytes with_motion_section(Bytes v1, std::uint32_t version, const Bytes& section) {
  put_u32(v1, version_offset, version);
  v1.insert(v1.end() - 4, section.begin(), section.end());
  reseal(v1);
  return v1;
}

}  // namespace ssl_formation::testing
