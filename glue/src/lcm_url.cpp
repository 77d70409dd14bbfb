#include "snapnav/glue/lcm_url.hpp"

#include <arpa/inet.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace snapnav::glue {
namespace {

std::string UrlParam(const std::string& url, const std::string& key) {
  const auto q = url.find('?');
  if (q == std::string::npos) return "";
  std::istringstream in(url.substr(q + 1));
  std::string kv;
  while (std::getline(in, kv, '&')) {
    const auto eq = kv.find('=');
    if (eq != std::string::npos && kv.substr(0, eq) == key) return kv.substr(eq + 1);
  }
  return "";
}

// Multicast group of a udpm URL in host byte order (0 if unparsable).
uint32_t UdpmGroup(const std::string& url) {
  const auto start = url.find("://");
  if (start == std::string::npos) return 0;
  std::string host = url.substr(start + 3);
  host = host.substr(0, host.find_first_of(":?"));
  in_addr a{};
  if (inet_pton(AF_INET, host.c_str(), &a) != 1) return 0;
  return ntohl(a.s_addr);
}

long ReadLong(const std::string& path) {
  std::ifstream in(path);
  long v = -1;
  if (!(in >> v)) return -1;
  return v;
}

// The interface of the route that carries `group`, empty if none (parses /proc/net/route).
std::string RouteFor(uint32_t group) {
  std::ifstream in("/proc/net/route");
  std::string line;
  std::getline(in, line);  // header
  std::string best;
  int best_bits = -1;
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::string iface, dest_hex, gw_hex, flags_hex, refcnt, use, metric, mask_hex;
    if (!(f >> iface >> dest_hex >> gw_hex >> flags_hex >> refcnt >> use >> metric >> mask_hex)) continue;
    const uint32_t dest = ntohl(static_cast<uint32_t>(std::stoul(dest_hex, nullptr, 16)));
    const uint32_t mask = ntohl(static_cast<uint32_t>(std::stoul(mask_hex, nullptr, 16)));
    if ((group & mask) != dest) continue;
    const int bits = __builtin_popcount(mask);
    if (bits > best_bits) {
      best_bits = bits;
      best = iface;
    }
  }
  return best;
}

}  // namespace

std::string DefaultLcmUrl() {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return (env && *env) ? env : kDefaultLcmUrl;
}

std::string DiagnoseLcmFailure(const std::string& url) {
  std::ostringstream out;
  out << "cannot create LCM on '" << url << "'.\n";
  const std::string provider = url.substr(0, url.find("://"));
  if (provider == "file") {
    std::string path = url.substr(7);
    path = path.substr(0, path.find('?'));
    out << "  The log file '" << path << "' cannot be opened (missing, unreadable, or not an LCM log;"
        << " for writing add ?mode=w).";
    return out.str();
  }
  if (provider != "udpm") {
    out << "  Check the provider and its options (snapnav uses udpm://, file://LOG?speed=0 and memq://).";
    return out.str();
  }
  const uint32_t group = UdpmGroup(url);
  std::ifstream flags_file("/sys/class/net/lo/flags");
  std::string flags_text;
  flags_file >> flags_text;
  const unsigned long flags = flags_text.empty() ? 0 : std::stoul(flags_text, nullptr, 16);
  const bool lo_up = flags & 0x1;
  const bool lo_multicast = flags & 0x1000;
  const std::string route = group ? RouteFor(group) : "";
  out << "  Facts: loopback is " << (lo_up ? "up" : "DOWN") << (lo_multicast ? " with" : " WITHOUT")
      << " multicast; the multicast group " << (route.empty() ? "has NO route" : "routes via " + route) << ".\n";
  out << "  LCM's UDP multicast needs a route for 224.0.0.0/4. To keep the bus on this host, either\n"
      << "  run the command in snapnav's private network namespace:\n"
      << "      ./snapnav bus -- <command>\n"
      << "  or give loopback the multicast route (as root):\n"
      << "      ip link set lo up multicast on\n"
      << "      ip route add 224.0.0.0/4 dev lo\n"
      << "  and keep ttl=0 in the URL. A LAN deployment over several machines routes 224.0.0.0/4 through\n"
      << "  the LAN interface (ip route add 224.0.0.0/4 dev eth0) and uses ttl=1 (see README).";
  return out.str();
}

std::string CheckReceiveBuffer(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0) return "";
  const std::string requested_text = UrlParam(url, "recv_buf_size");
  if (requested_text.empty()) return "";
  const long requested = std::atol(requested_text.c_str());
  const long rmem_max = ReadLong("/proc/sys/net/core/rmem_max");
  if (rmem_max < 0 || rmem_max >= requested) return "";
  std::ostringstream out;
  out << "warning: net.core.rmem_max is " << rmem_max << " bytes, below recv_buf_size=" << requested
      << " of the LCM URL: large messages (1 MB frames) may be dropped. Raise it with\n"
      << "    sudo sysctl -w net.core.rmem_max=" << 2 * requested << "\n"
      << "(persist it in /etc/sysctl.d/60-snapnav-lcm.conf; ./snapnav setup does both when run as root).";
  return out.str();
}

}  // namespace snapnav::glue
