#include "zip_writer.hpp"

#include <zip.h>

#include <ctime>
#include <stdexcept>

namespace mfbd {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what, zip_error_t* error) {
  throw std::runtime_error(path + ": " + what + ": " + zip_error_strerror(error));
}

// 1980-01-01 00:00 local time, the earliest a ZIP entry can carry: the same
// archive for the same entries (reproducible packing).
std::time_t zipEpoch() {
  std::tm t{};
  t.tm_year = 80;
  t.tm_mday = 1;
  t.tm_isdst = -1;
  return std::mktime(&t);
}

}  // namespace

void writeZip(const std::string& path, const std::vector<ZipEntry>& entries) {
  int code = 0;
  zip_t* archive = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
  if (!archive) {
    zip_error_t error;
    zip_error_init_with_code(&error, code);
    fail(path, "cannot open for writing", &error);
  }
  try {
    for (const ZipEntry& e : entries) {
      // The data stay in `entries` until zip_close reads them.
      zip_source_t* source = zip_source_buffer(archive, e.data.data(), e.data.size(), 0);
      if (!source) fail(path, e.name, zip_get_error(archive));
      const zip_int64_t index = zip_file_add(archive, e.name.c_str(), source, ZIP_FL_ENC_UTF_8);
      if (index < 0) {
        zip_source_free(source);
        fail(path, e.name, zip_get_error(archive));
      }
      const bool executable = e.name.size() > 3 && e.name.compare(e.name.size() - 3, 3, ".so") == 0;
      const zip_uint32_t mode = executable ? 0100755u : 0100644u;  // Unix mode
      if (zip_set_file_compression(archive, zip_uint64_t(index), ZIP_CM_DEFLATE, 9) != 0 ||
          zip_file_set_mtime(archive, zip_uint64_t(index), zipEpoch(), 0) != 0 ||
          zip_file_set_external_attributes(archive, zip_uint64_t(index), 0, ZIP_OPSYS_UNIX, mode << 16) != 0)
        fail(path, e.name, zip_get_error(archive));
    }
  } catch (...) {
    zip_discard(archive);
    throw;
  }
  if (zip_close(archive) != 0) {
    const std::string message = path + ": write failed: " + zip_error_strerror(zip_get_error(archive));
    zip_discard(archive);
    throw std::runtime_error(message);
  }
}

}  // namespace mfbd
