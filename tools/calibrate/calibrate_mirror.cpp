#include "calibrate_mirror.hpp"

#include <cmath>
#include <iomanip>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "snapnav/glue/image_msg.hpp"
#include "snapnav/glue/log_reader.hpp"
#include "snapnav/omni_frame_t.hpp"

namespace snapnav::calibrate {
namespace {

bool DecodeFrame(const glue::LogEvent& e, omni_frame_t* f) {
  try {
    return f->decode(e.data.data(), 0, static_cast<int>(e.data.size())) > 0;
  } catch (...) {
    return false;
  }
}

std::string Trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

std::string Number(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << (std::abs(v) < 5e-7 ? 0.0 : v);
  return s.str();
}

}  // namespace

std::vector<cv::Mat> LogFrames(const std::string& log_path, const std::string& channel, int max_frames) {
  if (max_frames < 1) throw std::invalid_argument("--frames must be >= 1");
  // First pass: which events are raw frames of the channel (the fingerprint and kind decide).
  std::vector<int64_t> events;
  std::map<std::string, int> other_channels;
  {
    glue::LogReader reader(log_path);
    glue::LogEvent e;
    while (reader.Next(&e)) {
      omni_frame_t f;
      if (!DecodeFrame(e, &f) || f.kind != omni_frame_t::RAW_OMNI) continue;
      if (e.channel == channel) {
        events.push_back(e.eventnum);
      } else {
        ++other_channels[e.channel];
      }
    }
  }
  if (events.empty()) {
    std::string others;
    for (const auto& [ch, n] : other_channels)
      others += (others.empty() ? "" : ", ") + ch + " (" + std::to_string(n) + ")";
    throw std::runtime_error(log_path + ": no raw omni frames on channel " + channel +
                             (others.empty() ? std::string(" (nor on any other channel)")
                                             : "; raw omni frames are on: " + others + " (--channel)"));
  }
  std::set<int64_t> wanted;
  const size_t n = std::min(events.size(), static_cast<size_t>(max_frames));
  for (size_t i = 0; i < n; ++i) wanted.insert(events[n == 1 ? 0 : i * (events.size() - 1) / (n - 1)]);
  std::vector<cv::Mat> frames;
  glue::LogReader reader(log_path);
  glue::LogEvent e;
  while (reader.Next(&e) && frames.size() < wanted.size()) {
    if (e.channel != channel || !wanted.count(e.eventnum)) continue;
    omni_frame_t f;
    if (!DecodeFrame(e, &f)) continue;
    try {
      frames.push_back(glue::FrameToImage(f));
    } catch (const std::exception& ex) {
      throw std::runtime_error(log_path + ": event " + std::to_string(e.eventnum) + " on " + channel + ": " +
                               ex.what());
    }
  }
  return frames;
}

cv::Mat MeanImage(const std::vector<cv::Mat>& frames) {
  if (frames.empty()) throw std::invalid_argument("no frames");
  if (frames.size() == 1) return frames.front();
  cv::Mat sum(frames.front().size(), CV_MAKETYPE(CV_32F, frames.front().channels()), cv::Scalar::all(0));
  for (const auto& f : frames) {
    if (f.size() != frames.front().size() || f.type() != frames.front().type()) {
      throw std::invalid_argument("the frames differ in size or type (" + std::to_string(f.cols) + "x" +
                                  std::to_string(f.rows) + " after " + std::to_string(frames.front().cols) + "x" +
                                  std::to_string(frames.front().rows) + ")");
    }
    cv::accumulate(f, sum);
  }
  cv::Mat mean;
  sum.convertTo(mean, frames.front().type(), 1.0 / frames.size());
  return mean;
}

std::string WithMirrorSection(const std::string& text, const nav::MirrorModel& m, const std::string& mask_path,
                              bool* mask_written) {
  constexpr double kDeg = M_PI / 180;
  const std::map<std::string, std::string> values{{"center_x_px", Number(m.center_x_px)},
                                                  {"center_y_px", Number(m.center_y_px)},
                                                  {"inner_radius_px", Number(m.inner_radius_px)},
                                                  {"outer_radius_px", Number(m.outer_radius_px)},
                                                  {"elevation_inner_deg", Number(m.elevation_inner_rad / kDeg)},
                                                  {"elevation_outer_deg", Number(m.elevation_outer_rad / kDeg)},
                                                  {"mask", mask_path}};
  std::istringstream in(text);
  std::ostringstream out;
  std::string line, section;
  bool found = false, wrote_mask = false;
  std::set<std::string> written;
  auto flush_missing = [&]() {
    // Keys the template's [mirror] lacks (but `mask`, which only some programs read).
    for (const auto& [key, value] : values) {
      if (key != "mask" && !written.count(key)) out << key << " = " << value << "\n";
    }
  };
  while (std::getline(in, line)) {
    const std::string t = Trim(line);
    if (!t.empty() && t[0] == '[') {
      if (section == "mirror") flush_missing();
      section = t.substr(1, t.find(']') == std::string::npos ? std::string::npos : t.find(']') - 1);
      if (section == "mirror") found = true;
      out << line << "\n";
      continue;
    }
    const auto eq = line.find('=');
    if (section == "mirror" && eq != std::string::npos && !t.empty() && t[0] != '#' && t[0] != ';') {
      const std::string key = Trim(line.substr(0, eq));
      const auto it = values.find(key);
      if (it != values.end()) {
        // Keep the comment after the value.
        std::string comment;
        const std::string rest = line.substr(eq + 1);
        const auto c = rest.find_first_of(";#");
        if (c != std::string::npos) comment = "  " + rest.substr(c);
        out << key << " = " << it->second << comment << "\n";
        written.insert(key);
        if (key == "mask") wrote_mask = true;
        continue;
      }
    }
    out << line << "\n";
  }
  if (section == "mirror") flush_missing();
  if (!found) {
    out << "\n[mirror]   ; calibrate-mirror\n";
    for (const auto& key : {"center_x_px", "center_y_px", "inner_radius_px", "outer_radius_px", "elevation_inner_deg",
                            "elevation_outer_deg", "mask"}) {
      out << key << " = " << values.at(key) << "\n";
    }
    wrote_mask = true;
  }
  if (mask_written) *mask_written = wrote_mask;
  return out.str();
}

}  // namespace snapnav::calibrate
