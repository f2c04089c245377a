// The errno text every layer shows is the C library's own, for known and unknown values alike.
#include <gtest/gtest.h>

#include <cerrno>
#include <thread>

#include "base/errno_text.h"

namespace hapticd::base {
namespace {

TEST(ErrnoText, IsTheCLibrarysText) {
  EXPECT_EQ(errno_text(ENOENT), "No such file or directory");
  EXPECT_EQ(errno_text(ENODEV), "No such device");
  EXPECT_EQ(errno_text(EACCES), "Permission denied");
}

TEST(ErrnoText, AnUnknownValueSaysWhichItWas) {
  EXPECT_EQ(errno_text(9999), "Unknown error 9999");
  EXPECT_EQ(errno_text(-1), "Unknown error -1");
}

TEST(ErrnoText, TwoThreadsAskingAtOnceEachGetTheirOwnText) {
  std::string a, b;
  std::thread other([&] {
    for (int i = 0; i < 10000; ++i) a = errno_text(7000 + i % 10);
  });
  for (int i = 0; i < 10000; ++i) b = errno_text(8000 + i % 10);
  other.join();
  EXPECT_EQ(a, "Unknown error 7009");
  EXPECT_EQ(b, "Unknown error 8009");
}

}  // namespace
}  // namespace hapticd::base
