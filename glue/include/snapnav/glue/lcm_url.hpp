#pragma once
// The default LCM URL and the diagnosis printed when LCM cannot be created.

#include <string>

namespace snapnav::glue {

// UDP multicast that stays on this host (ttl=0) with a 4 MiB receive buffer
// so 1 MB frames are not dropped. The kernel caps the buffer at
// net.core.rmem_max: raise it with `sysctl -w net.core.rmem_max=8388608`.
inline constexpr char kDefaultLcmUrl[] = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
inline constexpr int kRecommendedRecvBufBytes = 4194304;

// LCM_DEFAULT_URL if set, else kDefaultLcmUrl.
std::string DefaultLcmUrl();

// What is wrong with `url` as an LCM URL, "" when nothing is: an unknown provider; for udpm://
// an address that is not an IPv4 multicast group, a port that is not 1..65535, an option
// (ttl, recv_buf_size) that is not a number in range.
std::string LcmUrlProblem(const std::string& url);

// Explains why LCM on `url` could not be created and prints the commands that fix it: a
// malformed URL is named as such; for udpm:// the state of loopback and the multicast route
// of the network namespace this process runs in (read from the kernel, not from sysfs,
// which shows the namespace it was mounted in).
std::string DiagnoseLcmFailure(const std::string& url);

// What DiagnoseLcmFailure reads of the network namespace this process runs in.
struct NetworkFacts {
  bool lo_known = false;  // loopback's flags could be read
  bool lo_up = false;
  bool lo_multicast = false;
  std::string group_route;  // the interface whose route carries the URL's group; empty: none
};
NetworkFacts ReadNetworkFacts(const std::string& url);
// The diagnosis for `url` given `facts` (DiagnoseLcmFailure(url) reads them).
std::string DiagnoseLcmFailure(const std::string& url, const NetworkFacts& facts);

// A warning if the kernel will cap the receive buffer below what `url` asks for
// (empty if fine or not applicable).
std::string CheckReceiveBuffer(const std::string& url);

}  // namespace snapnav::glue
