#pragma once
// Sizing a job before allocating it: the memory the machine has free now, and the message a
// command gives when a job cannot fit (no std::bad_alloc reaches a user unexplained).

#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

namespace netlab {

// MemAvailable from /proc/meminfo (bytes): what can be allocated without swapping. Empty where
// the kernel does not say.
inline std::optional<double> AvailableMemoryBytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key, unit;
  double kib;
  while (meminfo >> key >> kib) {
    std::getline(meminfo, unit);
    if (key == "MemAvailable:") return kib * 1024.0;
  }
  return std::nullopt;
}

// "3.2 GB", "850 MB", "12 kB": the size a person reads.
inline std::string FormatBytes(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 5) bytes /= 1000.0, ++u;
  char text[32];
  std::snprintf(text, sizeof text, bytes < 10.0 && u > 0 ? "%.1f %s" : "%.0f %s", bytes, units[u]);
  return text;
}

// An empty string when `needed` bytes fit in the memory available now (or the kernel does not
// say); otherwise why not, as "needs ~40 GB, 21 GB available", for the caller to prefix with what
// it was sizing.
inline std::string MemoryShortfall(double needed) {
  const std::optional<double> available = AvailableMemoryBytes();
  if (!available || needed <= *available) return "";
  std::ostringstream os;
  os << "needs ~" << FormatBytes(needed) << ", " << FormatBytes(*available) << " available";
  return os.str();
}

}  // namespace netlab
