// glue::LogReader on intact, truncated and corrupted LCM logs: every intact event is read, the
// damage is reported with its byte offset, reading resumes after it.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "snapnav/glue/log_reader.hpp"
#include "snapnav/glue/log_writer.hpp"

namespace snapnav::glue {
namespace {

namespace fs = std::filesystem;

struct Written {
  std::string channel;
  int64_t timestamp_us;
  std::string data;
  uint64_t offset;  // of the sync word
  uint64_t end;
};

class LogReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("snapnav_log_reader_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    path_ = (dir_ / "in.lcmlog").string();
    LogWriter w(path_);
    uint64_t offset = 0;
    const std::vector<std::string> channels = {"ODOMETRY", "LASER_SCAN", "OMNI_FRAME", "X"};
    for (int i = 0; i < 12; ++i) {
      Written e;
      e.channel = channels[i % channels.size()];
      e.timestamp_us = 1000 + 100 * i;
      e.data.resize(static_cast<size_t>(i == 5 ? 0 : 13 * i + 7));
      for (size_t k = 0; k < e.data.size(); ++k) e.data[k] = static_cast<char>((k * 31 + i) & 0xff);
      e.offset = offset;
      e.end = offset + 28 + e.channel.size() + e.data.size();
      offset = e.end;
      w.WriteRaw(e.channel, e.timestamp_us, e.data);
      written_.push_back(e);
    }
    w.Close();
    bytes_ = ReadFile(path_);
    ASSERT_EQ(bytes_.size(), offset);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static std::string ReadFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  }
  std::string WriteDamaged(const std::string& bytes) {
    const std::string p = (dir_ / "damaged.lcmlog").string();
    std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
    return p;
  }
  static std::vector<LogEvent> ReadAll(LogReader& r) {
    std::vector<LogEvent> out;
    LogEvent e;
    while (r.Next(&e)) out.push_back(e);
    return out;
  }
  // The events read are exactly the written ones except those at `lost` (indices).
  void ExpectAllBut(const std::vector<LogEvent>& got, const std::set<size_t>& lost) {
    size_t g = 0;
    for (size_t i = 0; i < written_.size(); ++i) {
      if (lost.count(i)) continue;
      ASSERT_LT(g, got.size()) << "event " << i << " missing";
      EXPECT_EQ(got[g].channel, written_[i].channel) << "event " << i;
      EXPECT_EQ(got[g].timestamp_us, written_[i].timestamp_us) << "event " << i;
      EXPECT_EQ(got[g].data, written_[i].data) << "event " << i;
      EXPECT_EQ(got[g].offset, written_[i].offset) << "event " << i;
      ++g;
    }
    EXPECT_EQ(g, got.size());
  }
  static void PutBigEndian32(std::string* bytes, uint64_t at, uint32_t v) {
    for (int k = 0; k < 4; ++k) (*bytes)[at + k] = static_cast<char>((v >> (24 - 8 * k)) & 0xff);
  }

  fs::path dir_;
  std::string path_;
  std::string bytes_;
  std::vector<Written> written_;
};

TEST_F(LogReaderTest, IntactLogReadsEveryEventLikeLcm) {
  LogReader r(path_);
  const auto got = ReadAll(r);
  ExpectAllBut(got, {});
  EXPECT_FALSE(r.damaged());
  EXPECT_EQ(r.position(), r.file_size());
  lcm::LogFile lcm_log(path_, "r");
  size_t i = 0;
  while (const lcm::LogEvent* e = lcm_log.readNextEvent()) {
    ASSERT_LT(i, got.size());
    EXPECT_EQ(e->channel, got[i].channel);
    EXPECT_EQ(std::string(static_cast<const char*>(e->data), e->datalen), got[i].data);
    ++i;
  }
  EXPECT_EQ(i, got.size());
}

TEST_F(LogReaderTest, MissingFileNamesIt) {
  try {
    LogReader r((dir_ / "nope.lcmlog").string());
    FAIL() << "no error";
  } catch (const LogError& e) {
    EXPECT_NE(std::string(e.what()).find("nope.lcmlog"), std::string::npos) << e.what();
  }
}

TEST_F(LogReaderTest, TruncatedAtEveryLengthKeepsEveryCompleteEvent) {
  for (size_t cut = 0; cut < bytes_.size(); ++cut) {
    LogReader r(WriteDamaged(bytes_.substr(0, cut)));
    const auto got = ReadAll(r);
    std::set<size_t> lost;
    const Written* partial = nullptr;
    for (size_t i = 0; i < written_.size(); ++i) {
      if (written_[i].end > cut) lost.insert(i);
      if (written_[i].offset < cut && written_[i].end > cut) partial = &written_[i];
    }
    SCOPED_TRACE("cut at " + std::to_string(cut));
    ExpectAllBut(got, lost);
    if (!partial) {
      EXPECT_FALSE(r.damaged());
      continue;
    }
    ASSERT_EQ(r.damage().size(), 1u);
    EXPECT_EQ(r.damage()[0].kind, LogDamage::Kind::kTruncated) << r.damage()[0].what;
    EXPECT_EQ(r.damage()[0].offset, partial->offset);
    EXPECT_EQ(r.damage()[0].resumed_at, cut);
    const std::string text = DescribeLogDamage(r.path(), r.damage()[0], r.file_size());
    EXPECT_NE(text.find("damaged.lcmlog: byte " + std::to_string(partial->offset)), std::string::npos) << text;
    EXPECT_NE(text.find("truncated"), std::string::npos) << text;
  }
}

TEST_F(LogReaderTest, CorruptHeaderFieldsLoseOnlyThatEvent) {
  struct Case {
    const char* name;
    uint64_t field;   // offset in the header
    uint32_t value;   // written big-endian over 4 bytes
  };
  const std::vector<Case> cases = {
      {"sync word", 0, 0x12345678u},
      {"channel length 0", 20, 0},
      {"channel length 2^31-1", 20, 0x7fffffffu},
      {"negative channel length", 20, 0x80000000u},
      {"data length 2^31-1", 24, 0x7fffffffu},
      {"negative data length", 24, 0xffffffffu},
  };
  for (const auto& c : cases) {
    for (size_t k = 0; k < written_.size(); ++k) {
      SCOPED_TRACE(std::string(c.name) + " of event " + std::to_string(k));
      std::string bytes = bytes_;
      PutBigEndian32(&bytes, written_[k].offset + c.field, c.value);
      LogReader r(WriteDamaged(bytes));
      const auto got = ReadAll(r);
      ExpectAllBut(got, {k});
      ASSERT_EQ(r.damage().size(), 1u);
      EXPECT_EQ(r.damage()[0].offset, written_[k].offset);
      EXPECT_EQ(r.damage()[0].resumed_at, k + 1 < written_.size() ? written_[k + 1].offset : bytes.size());
    }
  }
}

TEST_F(LogReaderTest, WrongDataLengthIsDetectedByTheNextSyncWord) {
  for (size_t k = 0; k + 1 < written_.size(); ++k) {
    for (const int delta : {-3, -1, 1, 5, 40}) {
      const int64_t len = static_cast<int64_t>(written_[k].data.size()) + delta;
      if (len < 0) continue;
      SCOPED_TRACE("event " + std::to_string(k) + " data length " + std::to_string(delta));
      std::string bytes = bytes_;
      PutBigEndian32(&bytes, written_[k].offset + 24, static_cast<uint32_t>(len));
      LogReader r(WriteDamaged(bytes));
      auto got = ReadAll(r);
      ASSERT_EQ(r.damage().size(), 1u);
      if (delta > 0) {
        // Longer: the next event starts inside the claimed data, so this one is not trusted.
        ExpectAllBut(got, {k});
        EXPECT_EQ(r.damage()[0].offset, written_[k].offset);
        EXPECT_NE(r.damage()[0].what.find("an intact event starts at byte " + std::to_string(written_[k + 1].offset)),
                  std::string::npos)
            << r.damage()[0].what;
      } else {
        // Shorter: the event is read with a short payload (the message decoder rejects it as
        // truncated); the rest of its data is the damage, reported where it starts.
        ASSERT_EQ(got.size(), written_.size());
        EXPECT_EQ(got[k].data, written_[k].data.substr(0, static_cast<size_t>(len)));
        got[k].data = written_[k].data;
        ExpectAllBut(got, {});
        EXPECT_EQ(r.damage()[0].offset, written_[k].end + delta);
        EXPECT_EQ(r.damage()[0].resumed_at, written_[k + 1].offset);
      }
    }
  }
}

TEST_F(LogReaderTest, GarbageBetweenEventsIsSkippedAndCounted) {
  const size_t k = 4;
  const std::string garbage(777, '\x5a');
  std::string bytes = bytes_;
  bytes.insert(written_[k].offset, garbage);
  LogReader r(WriteDamaged(bytes));
  const auto got = ReadAll(r);
  ASSERT_EQ(got.size(), written_.size());
  for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].data, written_[i].data);
  ASSERT_EQ(r.damage().size(), 1u);
  EXPECT_EQ(r.damage()[0].kind, LogDamage::Kind::kCorrupt);
  EXPECT_EQ(r.damage()[0].offset, written_[k].offset);
  EXPECT_EQ(r.damage()[0].skipped_bytes(), garbage.size());
  EXPECT_EQ(r.damaged_bytes(), garbage.size());
  std::ostringstream report;
  r.ReportDamage(report, "tool");
  EXPECT_NE(report.str().find("tool: "), std::string::npos);
  EXPECT_NE(report.str().find("skipped 777 bytes, resumed at byte " + std::to_string(written_[k].offset + 777)),
            std::string::npos)
      << report.str();
}

TEST_F(LogReaderTest, RandomByteFlipsLoseAtMostTheEventHit) {
  std::mt19937 rng(20240607);
  for (int trial = 0; trial < 3000; ++trial) {
    std::string bytes = bytes_;
    const size_t at = std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(rng);
    bytes[at] = static_cast<char>(bytes[at] ^ (1 << std::uniform_int_distribution<int>(0, 7)(rng)));
    LogReader r(WriteDamaged(bytes));
    const auto got = ReadAll(r);
    SCOPED_TRACE("flip at " + std::to_string(at));
    size_t hit = 0;
    while (written_[hit].end <= at) ++hit;
    const bool in_data = at >= written_[hit].end - written_[hit].data.size();
    if (in_data) {  // the log format cannot see it: the payload decoder must
      ASSERT_EQ(got.size(), written_.size());
      EXPECT_FALSE(r.damaged());
      continue;
    }
    // A flipped byte of a header or channel: that event is lost (or, for the event number or
    // timestamp, read with the flipped value), all others are intact.
    EXPECT_GE(got.size() + 1, written_.size());
    std::set<uint64_t> offsets;
    for (const auto& e : got) offsets.insert(e.offset);
    for (size_t i = 0; i < written_.size(); ++i) {
      if (i != hit) {
        EXPECT_TRUE(offsets.count(written_[i].offset)) << "event " << i << " lost";
      }
    }
  }
}

// A file that is not an LCM log at all is an error when it is opened, naming it and what its start
// holds (it read as one damaged stretch over the whole file: no event, "damage", nothing said).
TEST_F(LogReaderTest, NotAnLcmLogIsAnErrorNamingTheFile) {
  std::string random;
  std::mt19937 rng(7);
  for (int i = 0; i < 100000; ++i) random.push_back(static_cast<char>(rng() & 0xff));
  random[0] = '\x42';
  const std::string gzip = std::string("\x1f\x8b\x08\x00", 4) + std::string(200, '\x01');
  struct Case {
    std::string bytes;
    std::string want;
  };
  for (const Case& c : {Case{random, "is not an LCM log: byte 0: no event sync word (it starts with 42 "},
                        Case{"FLASER 181 1.0 2.0\nODOM 1 2 3\n", "(it is text: 'FLASER 181 1.0 2.0')"},
                        Case{gzip, "(it is gzip-compressed: gunzip it first)"}}) {
    const std::string path = WriteDamaged(c.bytes);
    try {
      LogReader r(path);
      FAIL() << "no error for " << c.want;
    } catch (const LogError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path + " is not an LCM log: byte 0: ", 0), 0u) << what;
      EXPECT_NE(what.find(c.want), std::string::npos) << what;
      EXPECT_NE(what.find("none of its " + std::to_string(c.bytes.size()) + " bytes starts an intact event"),
                std::string::npos)
          << what;
    }
  }
}

// A log whose first event is damaged is a damaged log: the rest is read, the damage named.
TEST_F(LogReaderTest, DamagedFirstEventIsDamageNotAnError) {
  std::string bytes = bytes_;
  bytes[0] = 'X';
  LogReader r(WriteDamaged(bytes));
  ExpectAllBut(ReadAll(r), {0});
  ASSERT_EQ(r.damage().size(), 1u);
  EXPECT_EQ(r.damage()[0].offset, 0u);
  EXPECT_EQ(r.damage()[0].resumed_at, written_[1].offset);
  // An empty file is an empty log.
  LogReader empty(WriteDamaged(""));
  LogEvent e;
  EXPECT_FALSE(empty.Next(&e));
  EXPECT_FALSE(empty.damaged());
}

}  // namespace
}  // namespace snapnav::glue
