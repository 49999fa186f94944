// fmuResourceLocation -> path, in both hosts' conventions (pure string
// handling, so both are checked on any host).
#include <gtest/gtest.h>

#include "resource_uri.hpp"

namespace {

using mfbd::PathStyle;

std::string toPath(const std::string& uri, PathStyle style) {
  std::string path, why;
  EXPECT_TRUE(mfbd::resourceUriToPath(uri, path, why, style)) << uri << ": " << why;
  return path;
}

std::string refusal(const std::string& uri, PathStyle style) {
  std::string path = "unchanged", why;
  EXPECT_FALSE(mfbd::resourceUriToPath(uri, path, why, style)) << uri << " gave " << path;
  return why;
}

TEST(ResourceUri, PosixPathsKeepTheirLeadingSlash) {
  EXPECT_EQ(toPath("file:///tmp/fmu/resources", PathStyle::Posix), "/tmp/fmu/resources");
  EXPECT_EQ(toPath("file:/tmp/fmu/resources/", PathStyle::Posix), "/tmp/fmu/resources/");
  EXPECT_EQ(toPath("file://localhost/tmp/a%20b/r%C3%A9s", PathStyle::Posix), "/tmp/a b/r\xC3\xA9s");
}

TEST(ResourceUri, WindowsPathsStartWithTheDrive) {
  EXPECT_EQ(toPath("file:///C:/Users/me/fmu/resources", PathStyle::Windows), "C:/Users/me/fmu/resources");
  // Wine maps the Unix root to drive Z:.
  EXPECT_EQ(toPath("file:///Z:/tmp/with%20space/resources/", PathStyle::Windows), "Z:/tmp/with space/resources/");
  EXPECT_EQ(toPath("file:/d:/x", PathStyle::Windows), "d:/x");
  EXPECT_EQ(toPath("file://localhost/C%3A/x", PathStyle::Windows), "C:/x");
  EXPECT_EQ(toPath("file:///C:", PathStyle::Windows), "C:");
}

TEST(ResourceUri, WindowsStyleNeedsADriveLetter) {
  EXPECT_NE(refusal("file:///tmp/fmu", PathStyle::Windows).find("drive letter"), std::string::npos);
  refusal("file:///C/x", PathStyle::Windows);
  refusal("file:///1:/x", PathStyle::Windows);
}

TEST(ResourceUri, EscapedNulIsRefusedByName) {
  // Was decoded into the path, which the C library then cut at the NUL: a
  // different folder, reported as a GUID mismatch.
  for (PathStyle style : {PathStyle::Posix, PathStyle::Windows}) {
    const std::string why = refusal("file:///C:/a%00/../b", style);
    EXPECT_NE(why.find("%00"), std::string::npos) << why;
    EXPECT_NE(why.find("NUL"), std::string::npos) << why;
  }
}

TEST(ResourceUri, MalformedEscapesAreRefusedWithTheEscape) {
  for (const char* uri : {"file:///tmp/a%2", "file:///tmp/a%", "file:///tmp/a%zz/b", "file:///tmp/%2g"}) {
    const std::string why = refusal(uri, PathStyle::Posix);
    EXPECT_NE(why.find("malformed percent-escape"), std::string::npos) << why;
  }
  EXPECT_NE(refusal("file:///tmp/a%zz/b", PathStyle::Posix).find("\"%zz\""), std::string::npos);
}

TEST(ResourceUri, OtherSchemesAndHostsAreRefused) {
  refusal("http://example.org/r", PathStyle::Posix);
  refusal("file://server/share/r", PathStyle::Windows);
  refusal("file:relative/r", PathStyle::Posix);
}

}  // namespace
