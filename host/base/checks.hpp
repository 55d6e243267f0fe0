// The checks every command runs on its options before it does any work:
// a number within the range the hardware or the model can take, an output
// path that can be written, an input file that is text. One place, so that
// each refusal reads the same ("--feed = 1e5: above ...; expected ...") and
// no command finds a bad option only after a long capture.
#pragma once

#include <string>
#include <string_view>

namespace mc::host {

// A closed range [lo, hi] with the unit its numbers are in, for messages.
struct Bounds {
  double lo, hi;
  std::string_view unit = {};
};

// v unless it is outside r (or not finite): then InputError naming
// `quantity`, quoting `as_written` (the user's text; empty: v formatted) and
// saying "lo..hi unit"; `why` says where the bound comes from.
double require_in(double v, const Bounds& r, std::string_view quantity, std::string_view as_written = {},
                  std::string_view why = {});

// An output file a command will write at its end: InputError naming
// `option` unless its directory exists and is writable and the path is not
// a directory or a read-only file. Nothing is created.
void require_writable_file(const std::string& path, std::string_view option);
// An output directory: an existing writable directory, or one that can be
// created (its nearest existing ancestor is a writable directory).
void require_writable_dir(const std::string& path, std::string_view option);

// An input that must be text: InputError naming `option` and the file at the
// first byte that no text file holds (NUL or another control character
// besides tab, CR, LF, FF), with its offset and value. Unreadable files are
// left to the reader, which names them.
void require_text_file(const std::string& path, std::string_view option);

}  // namespace mc::host
