#include "zip_writer.hpp"

#include <array>
#include <cstdint>
#include <fstream>
#include <stdexcept>

namespace mfbd {

namespace {

std::uint32_t crc32(const std::string& data) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : data) c = table[(c ^ b) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

void put16(std::string& out, std::uint32_t v) {
  out += char(v & 0xFF);
  out += char((v >> 8) & 0xFF);
}
void put32(std::string& out, std::uint32_t v) {
  put16(out, v & 0xFFFF);
  put16(out, v >> 16);
}

}  // namespace

void writeZip(const std::string& path, const std::vector<ZipEntry>& entries) {
  std::string archive, central;
  const std::uint32_t dosTime = 0, dosDate = (1 << 5) | 1;  // 1980-01-01: reproducible archives
  for (const ZipEntry& e : entries) {
    if (archive.size() + e.data.size() > 0xF0000000u) throw std::runtime_error(path + ": archive over 4 GiB");
    const std::uint32_t crc = crc32(e.data), size = std::uint32_t(e.data.size());
    const std::uint32_t offset = std::uint32_t(archive.size());
    put32(archive, 0x04034b50);  // local file header
    put16(archive, 20);          // version needed
    put16(archive, 0x0800);      // flags: UTF-8 names
    put16(archive, 0);           // stored
    put16(archive, dosTime);
    put16(archive, dosDate);
    put32(archive, crc);
    put32(archive, size);
    put32(archive, size);
    put16(archive, std::uint32_t(e.name.size()));
    put16(archive, 0);
    archive += e.name;
    archive += e.data;

    put32(central, 0x02014b50);  // central directory header
    put16(central, (3 << 8) | 20);  // made by: Unix
    put16(central, 20);
    put16(central, 0x0800);
    put16(central, 0);
    put16(central, dosTime);
    put16(central, dosDate);
    put32(central, crc);
    put32(central, size);
    put32(central, size);
    put16(central, std::uint32_t(e.name.size()));
    put16(central, 0);
    put16(central, 0);
    put16(central, 0);
    put16(central, 0);
    const bool executable = e.name.size() > 3 && e.name.compare(e.name.size() - 3, 3, ".so") == 0;
    put32(central, (executable ? 0100755u : 0100644u) << 16);  // Unix mode
    put32(central, offset);
    central += e.name;
  }
  const std::uint32_t centralOffset = std::uint32_t(archive.size());
  archive += central;
  put32(archive, 0x06054b50);  // end of central directory
  put16(archive, 0);
  put16(archive, 0);
  put16(archive, std::uint32_t(entries.size()));
  put16(archive, std::uint32_t(entries.size()));
  put32(archive, std::uint32_t(central.size()));
  put32(archive, centralOffset);
  put16(archive, 0);

  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  out.write(archive.data(), std::streamsize(archive.size()));
  if (!out) throw std::runtime_error(path + ": write failed");
}

}  // namespace mfbd
