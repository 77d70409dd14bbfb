#pragma once
// The bus: typed publish/subscribe over LCM. A handler's exception or a payload
// that does not decode is counted per channel and reported; it never unwinds
// through LCM's C callback and never stops the process.

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "snapnav/glue/codec.hpp"

namespace snapnav::glue {

// Raised when LCM cannot be created; what() explains why and how to fix it.
class BusError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ChannelStats {
  uint64_t received = 0;        // messages delivered to a handler
  uint64_t decode_errors = 0;   // payloads rejected by the decoder
  uint64_t handler_errors = 0;  // handler threw
  uint64_t published = 0;
  std::string last_error;
};

// What the handler being run is handling (valid only inside a handler).
struct MessageInfo {
  std::string channel;
  int64_t recv_utime = 0;  // receive time stamped by LCM [microseconds]
  size_t size_bytes = 0;
};

class Bus {
 public:
  // Creates LCM on `url` (empty: LCM_DEFAULT_URL or DefaultLcmUrl()).
  // Throws BusError with a diagnosis when LCM cannot be created.
  explicit Bus(const std::string& url);
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;
  ~Bus();

  const std::string& url() const { return url_; }
  lcm::LCM& lcm() { return lcm_; }

  template <class Msg>
  void Publish(const std::string& channel, const Msg& msg) {
    if (lcm_.publish(channel, &msg) != 0) {
      throw std::runtime_error("publish on " + channel + " failed (" + std::to_string(msg.getEncodedSize()) +
                               " bytes)");
    }
    ++stats_[channel].published;
  }
  void PublishRaw(const std::string& channel, const void* data, size_t size);

  // LCM's own queue capacity per subscription [messages]: while the handlers lag further behind,
  // LCM drops that channel's messages for this subscriber (with no counter). Subscriptions to
  // small, high-rate messages (odometry at 50 Hz) pass a larger capacity.
  static constexpr int kDefaultQueueCapacity = 30;
  static constexpr int kOdometryQueueCapacity = 1000;  // 20 s of 50 Hz odometry (about 100 kB)

  // Subscribes a typed handler; `channel` is an exact name.
  template <class Msg>
  void Subscribe(const std::string& channel, std::function<void(const Msg&)> handler,
                 int queue_capacity = kDefaultQueueCapacity) {
    SubscribeRaw(
        channel,
        [this, handler = std::move(handler)](const void* data, size_t size) {
      std::string error;
      auto msg = Decode<Msg>(data, size, &error);
      if (!msg) {
        CountDecodeError(error);
        return;
      }
          handler(*msg);
        },
        queue_capacity);
  }
  template <class Msg, class Obj>
  void Subscribe(const std::string& channel, void (Obj::*method)(const Msg&), Obj* obj,
                 int queue_capacity = kDefaultQueueCapacity) {
    Subscribe<Msg>(channel, std::function<void(const Msg&)>([obj, method](const Msg& m) { (obj->*method)(m); }),
                   queue_capacity);
  }
  // Subscribes a handler on the raw payload; `channel` may be a regex as in LCM.
  void SubscribeRaw(const std::string& channel, std::function<void(const void*, size_t)> handler,
                    int queue_capacity = kDefaultQueueCapacity);

  // Handles at most one message; waits up to timeout_ms. Returns false on timeout
  // and at the end of a file:// log. Throws std::runtime_error when LCM itself fails.
  bool HandleOnce(int timeout_ms);
  // Handles messages until ShutdownRequested(), the end of a file:// log, or
  // `keep_going` returns false.
  void Run(const std::function<bool()>& keep_going = nullptr);
  // True once a file:// log has been read to its end.
  bool end_of_log() const { return end_of_log_; }

  // Information on the message whose handler is running.
  const MessageInfo& current() const { return current_; }

  const std::map<std::string, ChannelStats>& stats() const { return stats_; }
  uint64_t total_errors() const;
  // One line per channel: received, published, errors and the last reason.
  void ReportStats(std::ostream& out) const;

  // Channel of the message being handled gets one more decode error.
  void CountDecodeError(const std::string& reason);

 private:
  struct Subscription;
  void Dispatch(Subscription* sub, const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void CountHandlerError(const std::string& channel, const std::string& reason);

  std::string url_;
  lcm::LCM lcm_;
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
  std::map<std::string, ChannelStats> stats_;
  MessageInfo current_;
  bool reads_log_ = false;
  bool end_of_log_ = false;
};

}  // namespace snapnav::glue
