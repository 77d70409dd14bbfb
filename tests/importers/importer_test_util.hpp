#pragma once
// Helpers of the importer tests: a sink that keeps the messages, a temporary folder, files.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "importers.hpp"
#include "snapnav/glue/codec.hpp"

namespace snapnav::importers::testing {

struct Event {
  std::string channel;
  int64_t utime = 0;
  std::string payload;
};

// Keeps every message; Decoded<Msg>(channel) decodes those of one channel (a payload that
// does not decode fails the test).
class VectorSink : public Sink {
 public:
  void Write(const std::string& channel, int64_t utime, const std::string& payload) override {
    events.push_back({channel, utime, payload});
  }

  template <class Msg>
  std::vector<Msg> Decoded(const std::string& channel) const {
    std::vector<Msg> out;
    for (const auto& e : events) {
      if (e.channel != channel) continue;
      std::string error;
      auto msg = glue::Decode<Msg>(e.payload.data(), e.payload.size(), &error);
      EXPECT_TRUE(msg.has_value()) << channel << ": " << error;
      if (!msg) continue;
      EXPECT_EQ(msg->utime, e.utime) << "event time must be the message utime";
      out.push_back(std::move(*msg));
    }
    return out;
  }

  std::vector<Event> events;
};

// A fresh folder under $TMPDIR (or /tmp), removed with its contents at the end.
class TempDir {
 public:
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/snapnav_importers_XXXXXX";
    std::vector<char> buf(pattern.begin(), pattern.end());
    buf.push_back('\0');
    if (mkdtemp(buf.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = buf.data();
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string File(const std::string& name) const { return path_ + "/" + name; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

inline void WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  ASSERT_TRUE(out.good()) << path;
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// True if any error message contains `text`.
inline bool HasError(const ImportReport& report, const std::string& text) {
  for (const auto& e : report.errors) {
    if (e.find(text) != std::string::npos) return true;
  }
  return false;
}

inline std::string Errors(const ImportReport& report) {
  std::string all;
  for (const auto& e : report.errors) all += e + "\n";
  return all;
}

}  // namespace snapnav::importers::testing
