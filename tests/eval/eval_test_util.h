// eval_test_util.h: a fresh temporary folder per test for the evaluation tests.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace cenote::eval::test {

// Creates (after removing) <tmp>/cenote_eval_test/<suite>.<test>; removed again on destruction.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() / "cenote_eval_test" /
            (std::string(info->test_suite_name()) + "." + info->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  std::string operator/(const std::string& name) const { return (path_ / name).string(); }
  std::string str() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace cenote::eval::test
