// One line of G-code split into words: the lexical half of the interpreter.
// It knows the characters and the letters; which G and M numbers exist and
// what they do is the interpreter's business.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "host/gcode/error.hpp"

namespace mc::gcode {

struct Word {
  char letter = 0;   // upper case
  double value = 0;  // as written, in program units
  int column = 0;    // 1-based column of the letter
  std::string text;  // the word without blanks, upper case: "G38.2", "X-1.5"
};

struct Block {
  bool block_delete = false;                    // the line starts with '/'
  bool percent = false;                         // the line is a '%' program delimiter
  std::optional<Word> n;                        // line number
  std::vector<Word> g;                          // G words in the order written
  std::vector<Word> m;                          // M words in the order written
  std::array<std::optional<Word>, 26> words{};  // every other letter, at most once

  const std::optional<Word>& word(char letter) const { return words.at(static_cast<size_t>(letter - 'A')); }
  bool has(char letter) const { return word(letter).has_value(); }
  // The word's value; only call when has(letter).
  double value(char letter) const { return word(letter)->value; }
};

struct ParsedLine {
  Block block;
  std::optional<Error> error;  // file and line are left for the caller
};

// Splits a line into words. Blanks are ignored everywhere outside comments
// (as LinuxCNC and Grbl do: "G 0 1 X 1 . 5" is "G01 X1.5"); comments "( )" and
// "; ..." are dropped. Errors: characters that are no word, numbers that are
// not decimals, a word given twice, N not first, and the refused features
// (# parameters, [ ] expressions, O words, polar @ ^, other axes, D/H/E words).
ParsedLine parse_line(std::string_view text);

}  // namespace mc::gcode
