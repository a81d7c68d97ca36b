// The words of an enum: one table of {word, value} per enum, which a reader accepts (rail_core's
// MapReader::choice) and a writer or a message prints (wordOf), so that no word is written twice.
#pragma once

#include <cstddef>

namespace rail::contact {

template <class E>
struct Word {
  const char* text;
  E value;
};

// The word of v in `words`, "?" for a value without one.
template <class E, std::size_t N>
constexpr const char* wordOf(const Word<E> (&words)[N], E v) noexcept {
  for (const Word<E>& w : words)
    if (w.value == v) return w.text;
  return "?";
}

// True when `words` names every value from 0 to `last` (an enum numbered from 0), for a static_assert
// beside each table.
template <class E, std::size_t N>
constexpr bool namesEvery(const Word<E> (&words)[N], E last) noexcept {
  for (int i = 0; i <= static_cast<int>(last); ++i) {
    bool found = false;
    for (const Word<E>& w : words) found = found || static_cast<int>(w.value) == i;
    if (!found) return false;
  }
  return true;
}

}  // namespace rail::contact
