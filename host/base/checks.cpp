#include "host/base/checks.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "host/base/errors.hpp"

namespace mc::host {

double require_in(double v, const Bounds& r, std::string_view quantity, std::string_view as_written,
                  std::string_view why) {
  if (std::isfinite(v) && v >= r.lo && v <= r.hi) return v;
  std::string expected = format_number(r.lo) + ".." + format_number(r.hi);
  if (!r.unit.empty()) expected += " " + std::string(r.unit);
  if (!why.empty()) expected += " (" + std::string(why) + ")";
  const std::string value = as_written.empty() ? format_number(v) : quote(as_written);
  const char* problem = !std::isfinite(v) ? "not finite" : v < r.lo ? "below the range" : "above the range";
  throw InputError(std::string(quantity), value, expected, problem);
}

namespace {

std::string parent_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

bool is_dir(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool exists(const std::string& p) {
  struct stat st {};
  return ::stat(p.c_str(), &st) == 0;
}

void require_dir_writable(const std::string& dir, const std::string& path, std::string_view option) {
  if (!is_dir(dir))
    throw InputError(std::string(option), quote(path), "a path in an existing directory",
                     "no directory " + quote(dir));
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw InputError(std::string(option), quote(path), "a path in a writable directory",
                     "cannot write in " + quote(dir));
}

}  // namespace

void require_writable_file(const std::string& path, std::string_view option) {
  if (path.empty()) throw InputError(std::string(option), "\"\"", "a file path");
  if (is_dir(path)) throw InputError(std::string(option), quote(path), "a file path", "a directory");
  require_dir_writable(parent_of(path), path, option);
  if (exists(path) && ::access(path.c_str(), W_OK) != 0)
    throw InputError(std::string(option), quote(path), "a writable file", "read-only");
}

void require_writable_dir(const std::string& path, std::string_view option) {
  if (path.empty()) throw InputError(std::string(option), "\"\"", "a directory path");
  std::string p = path;
  while (p.size() > 1 && p.back() == '/') p.pop_back();
  if (exists(p)) {
    if (!is_dir(p)) throw InputError(std::string(option), quote(path), "a directory", "a file");
    if (::access(p.c_str(), W_OK | X_OK) != 0)
      throw InputError(std::string(option), quote(path), "a writable directory", "cannot write in it");
    return;
  }
  // Created at the end, with its parents: the nearest one that exists must take it.
  std::string up = p;
  do {
    up = parent_of(up);
  } while (!exists(up) && up != "." && up != "/");
  require_dir_writable(up, path, option);
}

void require_text_file(const std::string& path, std::string_view option) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  char buf[4096];
  long long offset = 0;
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    const std::streamsize n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      const auto u = static_cast<unsigned char>(buf[i]);
      if (u >= 0x20 || u == '\t' || u == '\n' || u == '\r' || u == '\f') continue;
      char b[96];
      std::snprintf(b, sizeof b, "byte 0x%02X at offset %lld is not text", unsigned(u), offset + i);
      throw InputError(std::string(option), quote(path), "a text file", b);
    }
    offset += n;
  }
}

}  // namespace mc::host
