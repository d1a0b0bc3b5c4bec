// "Did you mean" for typos: the candidate a word is closest to, by edit distance.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace softevo {

// Edit distance (optimal string alignment): insertions, deletions, substitutions of one
// character and swaps of two adjacent ones each count 1.
std::size_t edit_distance(const std::string& a, const std::string& b);
// The candidate nearest to `word` within max(1, |word| / 3) edits (first of equals), "" if none
// is that near: a typo, not another word.
std::string closest_word(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace softevo
