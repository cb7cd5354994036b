// Tests of src/core/output_file.cpp: safe file-name slugs, and files replaced only once complete.
#include "core/output_file.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "penumbra/error.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

TEST(FileNameSlug, KeepsSafeCharactersAndMakesEverythingElseOneComponent) {
  EXPECT_EQ(fileNameSlug("torus"), "torus");
  EXPECT_EQ(fileNameSlug("My Scene-2.v1"), "My_Scene-2.v1");
  EXPECT_EQ(fileNameSlug("../../etc/passwd"), "_.._etc_passwd");  // dots inside one component are harmless
  EXPECT_EQ(fileNameSlug("/abs/path"), "_abs_path");
  EXPECT_EQ(fileNameSlug(std::string("rock.obj\0", 9)), "rock.obj_");
  EXPECT_EQ(fileNameSlug("a#b?c%d"), "a_b_c_d");
  EXPECT_EQ(fileNameSlug("--help"), "help");  // never an option
  EXPECT_EQ(fileNameSlug(".hidden"), "hidden");
  EXPECT_EQ(fileNameSlug(".."), "scene");
  EXPECT_EQ(fileNameSlug(""), "scene");
  EXPECT_EQ(fileNameSlug("\xc3\xa9t\xc3\xa9"), "_t_");  // non-ASCII bytes
  EXPECT_EQ(fileNameSlug(std::string(300, 'x')).size(), 64u);
}

class ReplaceFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("penumbra_output_file_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string read(const fs::path& p) const {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  size_t entries() const {
    return static_cast<size_t>(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()));
  }
  fs::path dir_;
};

TEST_F(ReplaceFile, WritesBesideTheTargetAndRenamesOnlyWhenComplete) {
  const std::string target = (dir_ / "out.txt").string();
  std::ofstream(target) << "old";
  EXPECT_THROW(replaceFile(target,
                           [](const std::string& temp) {
                             std::ofstream(temp) << "half";
                             fail("the writer failed");
                           }),
               Error);
  EXPECT_EQ(read(target), "old");  // the previous file, whole
  EXPECT_EQ(entries(), 1u);        // and no temporary left
  replaceFile(target, [](const std::string& temp) { std::ofstream(temp) << "new"; });
  EXPECT_EQ(read(target), "new");
  EXPECT_EQ(entries(), 1u);
}

TEST_F(ReplaceFile, ReplacesALinkItselfAndRefusesReadOnlyFilesAndFolders) {
  std::ofstream(dir_ / "victim") << "keep";
  fs::create_symlink(dir_ / "victim", dir_ / "link");
  replaceFile((dir_ / "link").string(), [](const std::string& temp) { std::ofstream(temp) << "new"; });
  EXPECT_EQ(read(dir_ / "victim"), "keep");
  EXPECT_FALSE(fs::is_symlink(dir_ / "link"));
  EXPECT_EQ(read(dir_ / "link"), "new");

  std::ofstream(dir_ / "ro") << "mine";
  fs::permissions(dir_ / "ro", fs::perms::owner_read);
  EXPECT_THROW(replaceFile((dir_ / "ro").string(), [](const std::string& temp) { std::ofstream(temp) << "x"; }), Error);
  EXPECT_EQ(read(dir_ / "ro"), "mine");
  fs::create_directories(dir_ / "folder");
  EXPECT_THROW(replaceFile((dir_ / "folder").string(), [](const std::string& temp) { std::ofstream(temp) << "x"; }),
               Error);
  EXPECT_THROW(replaceFile((dir_ / "missing/x").string(), [](const std::string& temp) { std::ofstream(temp) << "x"; }),
               Error);
}

TEST_F(ReplaceFile, FileIdentitySeesThroughOtherNames) {
  std::ofstream(dir_ / "a") << "a";
  fs::create_symlink(dir_ / "a", dir_ / "b");
  ASSERT_TRUE(fileIdentity((dir_ / "a").string()));
  EXPECT_EQ(fileIdentity((dir_ / "a").string()), fileIdentity((dir_ / "b").string()));
  EXPECT_EQ(fileIdentity((dir_ / "a").string()), fileIdentity((dir_ / "." / "a").string()));
  std::ofstream(dir_ / "c") << "a";
  EXPECT_NE(fileIdentity((dir_ / "a").string()), fileIdentity((dir_ / "c").string()));
  EXPECT_FALSE(fileIdentity((dir_ / "none").string()));
}

}  // namespace
}  // namespace penumbra
