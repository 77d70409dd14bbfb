#include "snapnav/glue/bus.hpp"

#include <iomanip>
#include <iostream>
#include <stdexcept>

#include "snapnav/glue/lcm_url.hpp"
#include "snapnav/glue/shutdown.hpp"

namespace snapnav::glue {
namespace {

// First few errors of a channel are printed, then every 100th.
bool ShouldPrint(uint64_t count) { return count <= 5 || count % 100 == 0; }

std::string ResolveUrl(const std::string& url) { return url.empty() ? DefaultLcmUrl() : url; }

}  // namespace

struct Bus::Subscription {
  Bus* bus = nullptr;
  std::function<void(const void*, size_t)> handler;
  void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) { bus->Dispatch(this, rbuf, channel); }
};

Bus::Bus(const std::string& url) : url_(ResolveUrl(url)), lcm_(url_) {
  if (!lcm_.good()) throw BusError(DiagnoseLcmFailure(url_));
  reads_log_ = url_.rfind("file://", 0) == 0 && url_.find("mode=w") == std::string::npos &&
               url_.find("mode=a") == std::string::npos;
  if (const std::string warning = CheckReceiveBuffer(url_); !warning.empty()) std::cerr << warning << "\n";
}

Bus::~Bus() = default;

void Bus::PublishRaw(const std::string& channel, const void* data, size_t size) {
  if (lcm_.publish(channel, data, static_cast<unsigned int>(size)) != 0) {
    throw std::runtime_error("publish on " + channel + " failed (" + std::to_string(size) + " bytes)");
  }
  ++stats_[channel].published;
}

void Bus::SubscribeRaw(const std::string& channel, std::function<void(const void*, size_t)> handler,
                       int queue_capacity) {
  if (queue_capacity < 1) throw std::invalid_argument("subscription to '" + channel + "': queue capacity must be >= 1");
  auto sub = std::make_unique<Subscription>();
  sub->bus = this;
  sub->handler = std::move(handler);
  lcm::Subscription* lcm_sub = lcm_.subscribe(channel, &Subscription::OnMessage, sub.get());
  if (!lcm_sub) throw std::runtime_error("cannot subscribe to channel '" + channel + "'");
  if (lcm_sub->setQueueCapacity(queue_capacity) != 0) {
    throw std::runtime_error("cannot set the queue capacity of channel '" + channel + "'");
  }
  subscriptions_.push_back(std::move(sub));
}

void Bus::Dispatch(Subscription* sub, const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  current_.channel = channel;
  current_.recv_utime = rbuf->recv_utime;
  current_.size_bytes = rbuf->data_size;
  ++stats_[channel].received;
  // Nothing may unwind through LCM's C callback: count and report instead.
  try {
    sub->handler(rbuf->data, rbuf->data_size);
  } catch (const std::exception& e) {
    CountHandlerError(channel, e.what());
  } catch (...) {
    CountHandlerError(channel, "unknown exception");
  }
}

void Bus::CountDecodeError(const std::string& reason) {
  ChannelStats& s = stats_[current_.channel];
  ++s.decode_errors;
  s.last_error = reason;
  if (ShouldPrint(s.decode_errors)) {
    std::cerr << "bus: " << current_.channel << ": rejected message #" << s.decode_errors << ": " << reason << "\n";
  }
}

void Bus::CountHandlerError(const std::string& channel, const std::string& reason) {
  ChannelStats& s = stats_[channel];
  ++s.handler_errors;
  s.last_error = reason;
  if (ShouldPrint(s.handler_errors)) {
    std::cerr << "bus: " << channel << ": handler error #" << s.handler_errors << ": " << reason << "\n";
  }
}

bool Bus::HandleOnce(int timeout_ms) {
  if (end_of_log_) return false;
  const int r = lcm_.handleTimeout(timeout_ms);
  if (r < 0 && reads_log_) {  // LCM's log provider reports the end of the file as an error
    end_of_log_ = true;
    return false;
  }
  // A signal interrupting the wait (SIGINT, SIGTERM) is a shutdown, not a failure.
  if (r < 0 && ShutdownRequested()) return false;
  if (r < 0) throw std::runtime_error("LCM handle failed on " + url_);
  return r > 0;
}

void Bus::Run(const std::function<bool()>& keep_going) {
  while (!ShutdownRequested() && !end_of_log_ && (!keep_going || keep_going())) HandleOnce(100);
}

uint64_t Bus::total_errors() const {
  uint64_t n = 0;
  for (const auto& [_, s] : stats_) n += s.decode_errors + s.handler_errors;
  return n;
}

void Bus::ReportStats(std::ostream& out) const {
  for (const auto& [channel, s] : stats_) {
    out << "  " << std::left << std::setw(24) << channel << " received " << s.received << ", published "
        << s.published << ", rejected " << s.decode_errors << ", handler errors " << s.handler_errors;
    if (!s.last_error.empty()) out << " (last: " << s.last_error << ")";
    out << "\n";
  }
}

}  // namespace snapnav::glue
