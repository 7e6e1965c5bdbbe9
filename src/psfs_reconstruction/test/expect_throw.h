// Test helper: expects `f` to throw an E whose message contains `needle` (errors must say
// what is wrong, so the tests check the words, not only the type).
#pragma once

#include <gtest/gtest.h>

#include <exception>
#include <string>

namespace psfs_test {

template <typename E = std::exception, typename F>
void expectThrowContaining(F&& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "expected an exception mentioning '" << needle << "'";
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message '" << e.what() << "' lacks '" << needle << "'";
  }
}

}  // namespace psfs_test
