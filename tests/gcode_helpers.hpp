// Helpers for the G-code interpreter tests: run a program text, pick the
// motions out of the canonical calls, compare points.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <variant>
#include <vector>

#include "host/gcode/interpreter.hpp"

namespace gcode_test {

using namespace mc::gcode;

inline ProgramResult run(const std::string& text, const Options& options = {}) {
  return interpret_program(text, "t.ngc", options);
}

// The program must be accepted; returns its calls.
inline std::vector<CanonCall> calls_of(const std::string& text, const Options& options = {}) {
  ProgramResult r = run(text, options);
  EXPECT_TRUE(r.ok()) << (r.errors.empty() ? "" : r.errors.front().format()) << "\nprogram:\n" << text;
  return r.calls;
}

// The program must be refused; returns the first error.
inline Error error_of(const std::string& text) {
  ProgramResult r = run(text);
  EXPECT_FALSE(r.ok()) << "accepted:\n" << text;
  EXPECT_TRUE(r.calls.empty());
  return r.errors.empty() ? Error{} : r.errors.front();
}

inline std::vector<CanonOp> motions(const std::vector<CanonCall>& calls) {
  std::vector<CanonOp> out;
  for (const CanonCall& c : calls)
    if (is_motion(c.op)) out.push_back(c.op);
  return out;
}

inline Vec3 end_of(const CanonOp& op) {
  if (const auto* t = std::get_if<StraightTraverse>(&op)) return t->end;
  if (const auto* f = std::get_if<StraightFeed>(&op)) return f->end;
  if (const auto* a = std::get_if<ArcFeed>(&op)) return a->end;
  if (const auto* p = std::get_if<StraightProbe>(&op)) return p->end;
  ADD_FAILURE() << "not a motion";
  return {};
}

// Every motion end, in order.
inline std::vector<Vec3> ends(const std::vector<CanonCall>& calls) {
  std::vector<Vec3> out;
  for (const CanonOp& op : motions(calls)) out.push_back(end_of(op));
  return out;
}

inline ::testing::AssertionResult near3(const Vec3& a, const Vec3& b, double tol = 1e-9) {
  for (int i = 0; i < 3; ++i)
    if (!(std::fabs(a.at(i) - b.at(i)) <= tol))
      return ::testing::AssertionFailure() << "(" << a[0] << "," << a[1] << "," << a[2] << ") vs (" << b[0]
                                           << "," << b[1] << "," << b[2] << ")";
  return ::testing::AssertionSuccess();
}

template <typename T>
std::vector<T> only(const std::vector<CanonCall>& calls) {
  std::vector<T> out;
  for (const CanonCall& c : calls)
    if (const auto* p = std::get_if<T>(&c.op)) out.push_back(*p);
  return out;
}

}  // namespace gcode_test
