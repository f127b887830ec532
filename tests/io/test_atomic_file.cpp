// Files written whole or not at all (model/io/atomic_file.hpp): the target holds either its old contents
// or the new ones, never a part, and no temporary is left beside it, whether the write succeeds or fails.
#include <sys/stat.h>

#include <dirent.h>
#include <unistd.h>

#include <algorithm>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/io/atomic_file.hpp"

namespace jointcomp {
namespace {

// A fresh, empty folder per test.
class AtomicFile : public ::testing::Test {
protected:
  void SetUp() override {
    char pattern[] = "/tmp/jointcomp-atomic-XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    folder_ = pattern;
  }
  void TearDown() override {
    for (const std::string& name : entries()) ::unlink((folder_ + "/" + name).c_str());
    ::rmdir((folder_ + "/a folder").c_str());
    ::rmdir(folder_.c_str());
  }
  std::set<std::string> entries() const {
    std::set<std::string> names;
    DIR* dir = ::opendir(folder_.c_str());
    if (!dir) return names;
    while (const dirent* entry = ::readdir(dir)) {
      const std::string name = entry->d_name;
      if (name != "." && name != "..") names.insert(name);
    }
    ::closedir(dir);
    return names;
  }
  std::string folder_;
};

TEST_F(AtomicFile, WritesAndReplacesWholeFilesWithoutTemporaries) {
  const std::string path = folder_ + "/out.txt";
  writeFileAtomically(path, "first");
  EXPECT_EQ(readTextFile(path, "file"), "first");
  const std::string large(3 << 20, 'x');  // several writes' worth
  writeFileAtomically(path, large);
  EXPECT_EQ(readTextFile(path, "file"), large);
  writeFileAtomically(path, "");
  EXPECT_EQ(readTextFile(path, "file"), "");
  EXPECT_EQ(entries(), std::set<std::string>{"out.txt"});
}

TEST_F(AtomicFile, NewFilesGetTheUsualPermissions) {
  const mode_t mask = ::umask(022);
  writeFileAtomically(folder_ + "/out.txt", "text");
  ::umask(mask);
  struct stat info {};
  ASSERT_EQ(::stat((folder_ + "/out.txt").c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0644u);
}

TEST_F(AtomicFile, AFailedWriteKeepsTheOldContentsAndLeavesNothingBehind) {
  EXPECT_THROW(writeFileAtomically(folder_ + "/no such folder/out.txt", "text"), Error);
  // A folder cannot be replaced by a file: the rename fails after the contents were written.
  ASSERT_EQ(::mkdir((folder_ + "/a folder").c_str(), 0755), 0);
  try {
    writeFileAtomically(folder_ + "/a folder", "text");
    ADD_FAILURE() << "a folder was replaced by a file";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("a folder"), std::string::npos) << error.what();
  }
  EXPECT_EQ(entries(), std::set<std::string>{"a folder"});
}

TEST_F(AtomicFile, ConcurrentWritersOfOnePathLeaveOneWholeVersion) {
  const std::string path = folder_ + "/shared.txt";
  std::vector<std::string> versions;
  for (char c : std::string("abcd")) versions.push_back(std::string(1 << 18, c));
  std::vector<std::thread> writers;
  for (const std::string& contents : versions) {
    writers.emplace_back([&path, &contents] {
      for (int k = 0; k < 20; ++k) writeFileAtomically(path, contents);
    });
  }
  for (std::thread& writer : writers) writer.join();
  const std::string result = readTextFile(path, "file");
  EXPECT_NE(std::find(versions.begin(), versions.end(), result), versions.end()) << "a mixed or partial file";
  EXPECT_EQ(entries(), std::set<std::string>{"shared.txt"});
}

}  // namespace
}  // namespace jointcomp
