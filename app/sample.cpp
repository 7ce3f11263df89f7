// The sample catalogue and the default frame update.
#include "sample.h"

#include <algorithm>
#include <cctype>

#include "physics_loop.h"

namespace pba::app {

namespace {

// the catalogue lives in a function so registration order across files does not matter
std::vector<SampleEntry>& catalogue() {
  static std::vector<SampleEntry> entries;
  return entries;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string valid_names() {
  std::string list;
  for (const SampleEntry& e : Samples()) list += "\n  " + e.full_name();
  return list;
}

}  // namespace

void Sample::Update(double frame_dt) { ctx_.physics->advance(frame_dt); }

int RegisterSample(const char* category, const char* name, SampleFactory create) {
  auto& entries = catalogue();
  entries.push_back(SampleEntry{category, name, create});
  // keep the menu order stable: by category, then name
  std::stable_sort(entries.begin(), entries.end(), [](const SampleEntry& a, const SampleEntry& b) {
    return a.category != b.category ? a.category < b.category : a.name < b.name;
  });
  return static_cast<int>(entries.size());
}

std::span<const SampleEntry> Samples() { return catalogue(); }

int FindSample(std::string_view query, std::string* error) {
  const auto all = Samples();
  const std::string q = lower(query);
  // exact full name or exact name
  for (std::size_t i = 0; i < all.size(); ++i)
    if (lower(all[i].full_name()) == q || lower(all[i].name) == q) return static_cast<int>(i);
  // unique substring
  int found = -1;
  std::string matches;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (q.empty() || lower(all[i].full_name()).find(q) == std::string::npos) continue;
    matches += "\n  " + all[i].full_name();
    found = found == -1 ? static_cast<int>(i) : -2;
  }
  if (found >= 0) return found;
  if (found == -2)
    *error = "--sample '" + std::string(query) + "' matches several samples:" + matches;
  else
    *error = "--sample '" + std::string(query) + "': no such sample; valid names:" + valid_names();
  return -1;
}

std::string SampleSlug(const SampleEntry& e) {
  std::string s;
  for (char c : e.full_name()) {
    if (std::isalnum(static_cast<unsigned char>(c))) s += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!s.empty() && s.back() != '_') s += '_';
  }
  while (!s.empty() && s.back() == '_') s.pop_back();
  return s;
}

}  // namespace pba::app

namespace pba::app {

std::string UnknownOptions(const SampleContext& ctx, const SampleEntry& e) {
  // the given keys the sample never asked for, with the ones it reads
  std::string unknown;
  for (const auto& [key, value] : ctx.options)
    if (!ctx.option_keys.count(key)) unknown += (unknown.empty() ? "" : ", ") + key + "=" + value;
  if (unknown.empty()) return {};
  std::string keys;
  for (const std::string& k : ctx.option_keys) keys += (keys.empty() ? "" : ", ") + k;
  return "--option " + unknown + ": " + e.full_name() + " has no such option" +
         (keys.empty() ? std::string("; it takes no --option keys") : "; its keys: " + keys);
}

}  // namespace pba::app
