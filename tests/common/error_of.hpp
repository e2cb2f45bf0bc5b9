#pragma once
// Test helper: the one-line message of the mmlio::Error that f throws, or a text saying none was
// thrown (which no test expects to find its words in).
#include <functional>
#include <string>

#include "mmlio/core/error.hpp"

namespace mmlio::testing {

inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "<no mmlio::Error thrown>";
}

}  // namespace mmlio::testing

/// The statement throws an mmlio::Error whose message contains `text`.
#define EXPECT_ERROR_CONTAINS(statement, text)                              \
  do {                                                                      \
    const std::string msg_ = ::mmlio::testing::errorOf([&] { statement; }); \
    EXPECT_NE(msg_.find(text), std::string::npos) << "message: " << msg_;   \
  } while (0)
