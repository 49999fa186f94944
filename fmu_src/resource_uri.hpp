#pragma once
#include <string>

namespace mfbd {

// How the host names files: a POSIX path (/dir/x) or a Windows one, with a
// drive letter (C:/dir/x).
enum class PathStyle { Posix, Windows };

#ifdef _WIN32
constexpr PathStyle kHostPathStyle = PathStyle::Windows;
#else
constexpr PathStyle kHostPathStyle = PathStyle::Posix;
#endif

// fmuResourceLocation -> local directory path. Accepts file:/p, file:///p and
// file://localhost/p, with percent-escapes (spaces, UTF-8). In the Windows
// style the path starts with a drive letter, which the URI writes after a
// slash (file:///C:/dir -> C:/dir). Returns false with a reason for anything
// else (other schemes, remote hosts, malformed escapes, an escaped NUL).
bool resourceUriToPath(const std::string& uri, std::string& path, std::string& why,
                       PathStyle style = kHostPathStyle);

}  // namespace mfbd
