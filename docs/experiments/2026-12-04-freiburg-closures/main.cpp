// Ad-hoc check (not part of snapnav): MRPT's ICP on two FLASER scans of a CARMEN log, started at
// the log's own relative pose; prints how far ICP moves it.
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPosePDF.h>
#include <mrpt/slam/CICP.h>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>
struct Scan { std::vector<double> r; double x, y, t; };
int main(int argc, char** argv) {
  std::ifstream in(argv[1]);
  std::vector<Scan> scans;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("FLASER ", 0) != 0) continue;
    std::istringstream s(line.substr(7));
    int n; s >> n; Scan sc; sc.r.resize(n);
    for (auto& v : sc.r) s >> v;
    s >> sc.x >> sc.y >> sc.t;
    scans.push_back(sc);
  }
  const int w = std::atoi(getenv("W") ? getenv("W") : "0");
  auto map = [&](int c) {
    mrpt::maps::CSimplePointsMap m;
    const mrpt::poses::CPose2D pc(scans[c].x, scans[c].y, scans[c].t);
    for (int j = std::max(0, c - w); j <= std::min<int>(scans.size() - 1, c + w); ++j) {
      const Scan& sc = scans[j];
      const mrpt::poses::CPose2D rel = mrpt::poses::CPose2D(sc.x, sc.y, sc.t) - pc;
      const int n = sc.r.size();
      for (int i = 0; i < n; ++i) {
        if (sc.r[i] > 40 || sc.r[i] < 0.05) continue;
        const double a = -M_PI / 2 + M_PI * i / (n - 1);
        double gx, gy;
        rel.composePoint(sc.r[i] * std::cos(a), sc.r[i] * std::sin(a), gx, gy);
        m.insertPoint(gx, gy, 0);
      }
    }
    return m;
  };
  for (int k = 2; k + 1 < argc; k += 2) {
    const int a = std::atoi(argv[k]), b = std::atoi(argv[k + 1]);
    const Scan &A = scans[a], &B = scans[b];
    mrpt::poses::CPose2D pa(A.x, A.y, A.t), pb(B.x, B.y, B.t);
    const mrpt::poses::CPose2D rel = pb - pa;  // b in a's frame, as the reference has it
    auto ma = map(a), mb = map(b);
    mrpt::slam::CICP icp;
    icp.options.maxIterations = 200;
    icp.options.thresholdDist = 0.5;
    icp.options.thresholdAng = 5 * M_PI / 180;
    icp.options.ALFA = 0.5;
    icp.options.smallestThresholdDist = 0.02;
    mrpt::slam::CICP::TReturnInfo info;
    auto pdf = icp.Align(&ma, &mb, rel, info);
    const mrpt::poses::CPose2D est = pdf->getMeanVal();
    double dth = (est.phi() - rel.phi()) * 180 / M_PI;
    while (dth > 180) dth -= 360;
    while (dth < -180) dth += 360;
    std::cout << a << " " << b << ": ICP moves the reference's relative pose by " << std::hypot(est.x() - rel.x(), est.y() - rel.y())
              << " m, " << dth << " deg (goodness " << info.goodness << ", " << info.nIterations << " iterations)\n";
  }
}
