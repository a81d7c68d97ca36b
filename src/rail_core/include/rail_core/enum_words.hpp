// The words of an enum in a text file: one table per enum of {word, value}, which the reader accepts
// (MapReader::choice) and the writer prints (wordOf), so that no word is written twice.
#pragma once

#include <cstddef>

namespace rail::core {

template <class E>
struct Word {
  const char* text;
  E value;
};

// The word of v in `words`, "?" for a value without one.
template <class E, std::size_t N>
const char* wordOf(const Word<E> (&words)[N], E v) {
  for (const Word<E>& w : words)
    if (w.value == v) return w.text;
  return "?";
}

}  // namespace rail::core
