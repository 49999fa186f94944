#pragma once
#include <string>

namespace mfbd {

// fmuResourceLocation -> local directory path. Accepts file:/p, file:///p and
// file://localhost/p, with percent-escapes (spaces, UTF-8). Returns false
// with a reason for anything else (other schemes, remote hosts, bad escapes).
bool resourceUriToPath(const std::string& uri, std::string& path, std::string& why);

}  // namespace mfbd
