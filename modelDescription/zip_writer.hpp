// The FMU archive: entries compressed with deflate (libzip).
#pragma once
#include <string>
#include <vector>

namespace mfbd {

struct ZipEntry {
  std::string name;  // path inside the archive, '/' separated
  std::string data;
};

// Throws std::runtime_error naming the file if it cannot be written.
void writeZip(const std::string& path, const std::vector<ZipEntry>& entries);

}  // namespace mfbd
