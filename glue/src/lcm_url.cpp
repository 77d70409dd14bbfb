#include "snapnav/glue/lcm_url.hpp"

#include <arpa/inet.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "snapnav/glue/suggest.hpp"

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

// A whole non-negative decimal number (no sign, no trailing characters), or nullopt.
std::optional<long long> WholeNumber(const std::string& text) {
  if (text.empty() || text.size() > 18) return std::nullopt;
  for (const char c : text) {
    if (c < '0' || c > '9') return std::nullopt;
  }
  return std::stoll(text);
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

// The interface of the route that carries `group`, empty if none (parses /proc/net/route, which
// is this process's network namespace's table).
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

// The flags of interface `name` in this process's network namespace (SIOCGIFFLAGS), nullopt if
// they cannot be read. /sys/class/net/NAME/flags would show the namespace sysfs was mounted in:
// the host's, inside `./snapnav bus`.
std::optional<unsigned> InterfaceFlags(const char* name) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return std::nullopt;
  ifreq request{};
  std::strncpy(request.ifr_name, name, IFNAMSIZ - 1);
  const int rc = ::ioctl(fd, SIOCGIFFLAGS, &request);
  ::close(fd);
  if (rc != 0) return std::nullopt;
  return static_cast<unsigned short>(request.ifr_flags);
}

}  // namespace

std::string DefaultLcmUrl() {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  return (env && *env) ? env : kDefaultLcmUrl;
}

std::string LcmUrlProblem(const std::string& url) {
  const auto sep = url.find("://");
  if (sep == std::string::npos)
    return "not a URL PROVIDER://NETWORK?OPTIONS (e.g. " + std::string(kDefaultLcmUrl) + ")";
  const std::string provider = url.substr(0, sep);
  if (provider == "file" || provider == "memq" || provider == "tcpq") return "";
  if (provider != "udpm") {
    return "unknown provider '" + provider + "'" + DidYouMean(provider, {"udpm", "file", "memq", "tcpq"}) +
           " (snapnav uses udpm://, file://LOG?speed=0 and memq://)";
  }
  const std::string rest = url.substr(sep + 3);
  const std::string network = rest.substr(0, rest.find('?'));
  const std::string address = network.substr(0, network.find(':'));
  in_addr a{};
  if (address.empty()) return "no multicast group in '" + network + "' (udpm://GROUP:PORT, e.g. 239.255.76.67:7667)";
  if (inet_pton(AF_INET, address.c_str(), &a) != 1) {
    return "the group '" + address + "' is not an IPv4 address (udpm://GROUP:PORT, e.g. 239.255.76.67:7667)";
  }
  if ((ntohl(a.s_addr) >> 28) != 0xE) return "the group " + address + " is not a multicast address (224.0.0.0/4)";
  if (const auto colon = network.find(':'); colon != std::string::npos) {
    const std::string port = network.substr(colon + 1);
    const auto n = WholeNumber(port);
    if (!n || *n < 1 || *n > 65535) return "the port '" + port + "' is not a port number (1..65535)";
  }
  if (const auto q = rest.find('?'); q != std::string::npos) {
    std::istringstream in(rest.substr(q + 1));
    std::string kv;
    while (std::getline(in, kv, '&')) {
      const auto eq = kv.find('=');
      const std::string key = kv.substr(0, eq);
      const std::string value = eq == std::string::npos ? "" : kv.substr(eq + 1);
      const auto n = WholeNumber(value);
      if (key == "ttl" && (!n || *n > 255)) return "ttl '" + value + "' is not 0..255";
      if (key == "recv_buf_size" && (!n || *n < 1))
        return "recv_buf_size '" + value + "' is not a positive number of bytes";
    }
  }
  return "";
}

NetworkFacts ReadNetworkFacts(const std::string& url) {
  NetworkFacts facts;
  if (const std::optional<unsigned> flags = InterfaceFlags("lo")) {
    facts.lo_known = true;
    facts.lo_up = *flags & IFF_UP;
    facts.lo_multicast = *flags & IFF_MULTICAST;
  }
  if (const uint32_t group = UdpmGroup(url)) facts.group_route = RouteFor(group);
  return facts;
}

std::string DiagnoseLcmFailure(const std::string& url) {
  const bool udpm = url.rfind("udpm://", 0) == 0 && LcmUrlProblem(url).empty();
  return DiagnoseLcmFailure(url, udpm ? ReadNetworkFacts(url) : NetworkFacts{});
}

std::string DiagnoseLcmFailure(const std::string& url, const NetworkFacts& facts) {
  std::ostringstream out;
  out << "cannot create LCM on '" << url << "'.\n";
  if (const std::string problem = LcmUrlProblem(url); !problem.empty()) {
    out << "  The URL is malformed: " << problem << ".\n"
        << "  snapnav's default: " << kDefaultLcmUrl << " (--lcm-url or LCM_DEFAULT_URL set another).";
    return out.str();
  }
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
  const std::string& route = facts.group_route;
  out << "  Facts (this network namespace): ";
  if (facts.lo_known) {
    out << "loopback is " << (facts.lo_up ? "up" : "DOWN") << (facts.lo_multicast ? " with" : " WITHOUT")
        << " multicast";
  } else {
    out << "loopback's state could not be read";
  }
  out << "; the multicast group " << (route.empty() ? "has NO route" : "routes via " + route) << ".\n";
  const bool lo_unusable = facts.lo_known && (!facts.lo_up || !facts.lo_multicast);
  if (route.empty() || (route == "lo" && lo_unusable)) {
    out << "  LCM's UDP multicast needs a route for 224.0.0.0/4. To keep the bus on this host, either\n"
        << "  run the command in snapnav's private network namespace:\n"
        << "      ./snapnav bus -- <command>\n"
        << "  or give loopback the multicast route (as root):\n"
        << "      ip link set lo up multicast on\n"
        << "      ip route add 224.0.0.0/4 dev lo\n"
        << "  and keep ttl=0 in the URL. A LAN deployment over several machines routes 224.0.0.0/4 through\n"
        << "  the LAN interface (ip route add 224.0.0.0/4 dev eth0) and uses ttl=1 (docs/bus_and_launch.md).";
  } else {
    out << "  The URL is well-formed and the group has a route: LCM's own message above says what failed.\n"
        << "  If it is LCM's self test, multicast sent on " << route << " does not come back (a firewall, a\n"
        << "  switch): keep the bus on this host with ./snapnav bus -- <command>, or route 224.0.0.0/4\n"
        << "  through loopback (ip route add 224.0.0.0/4 dev lo, as root) and keep ttl=0.";
  }
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
