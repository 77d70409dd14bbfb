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

// Explains why LCM on `url` could not be created and prints the commands that fix it.
std::string DiagnoseLcmFailure(const std::string& url);

// A warning if the kernel will cap the receive buffer below what `url` asks for
// (empty if fine or not applicable).
std::string CheckReceiveBuffer(const std::string& url);

}  // namespace snapnav::glue
