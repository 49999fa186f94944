#include "resource_uri.hpp"

#include <cctype>

namespace mfbd {

namespace {
int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}
}  // namespace

bool resourceUriToPath(const std::string& uri, std::string& path, std::string& why, PathStyle style) {
  const std::string scheme = "file:";
  if (uri.size() < scheme.size() || uri.compare(0, scheme.size(), scheme) != 0) {
    why = "expected a file: URI, got \"" + uri + "\"";
    return false;
  }
  std::string rest = uri.substr(scheme.size());
  if (rest.rfind("//", 0) == 0) {  // authority: empty or localhost
    const std::size_t slash = rest.find('/', 2);
    const std::string host = rest.substr(2, slash == std::string::npos ? std::string::npos : slash - 2);
    if (!host.empty() && host != "localhost") {
      why = "resource location names remote host \"" + host + "\"; only local files are supported";
      return false;
    }
    rest = slash == std::string::npos ? "/" : rest.substr(slash);
  }
  if (rest.empty() || rest[0] != '/') {
    why = "expected an absolute path in \"" + uri + "\"";
    return false;
  }
  path.clear();
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (rest[i] != '%') {
      path += rest[i];
      continue;
    }
    const int hi = i + 2 < rest.size() ? hexValue(rest[i + 1]) : -1;
    const int lo = i + 2 < rest.size() ? hexValue(rest[i + 2]) : -1;
    if (hi < 0 || lo < 0) {
      why = "malformed percent-escape \"" + rest.substr(i, 3) + "\" in \"" + uri +
            "\" (expected % and two hexadecimal digits)";
      return false;
    }
    if (hi == 0 && lo == 0) {
      // A NUL would end the path early for the C library: another file.
      why = "percent-escape \"%00\" (a NUL character) in \"" + uri + "\" cannot be part of a file name";
      return false;
    }
    path += char(hi * 16 + lo);
    i += 2;
  }
  if (style == PathStyle::Windows) {
    // "/C:/dir" -> "C:/dir"; the drive letter is checked after decoding,
    // since a URI may escape the colon (file:///C%3A/dir).
    const bool drive = path.size() >= 3 && std::isalpha(static_cast<unsigned char>(path[1])) && path[2] == ':' &&
                       (path.size() == 3 || path[3] == '/' || path[3] == '\\');
    if (!drive) {
      why = "expected a drive letter in \"" + uri + "\" (as in file:///C:/dir)";
      return false;
    }
    path.erase(0, 1);
  }
  return true;
}

}  // namespace mfbd
