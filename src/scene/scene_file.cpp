// The JSON scene-file reader (docs/scene-format.md): the file, its syntax, the version
// and the top-level arrays, each read one item at a time by its module's reader
// (read_world.cpp, read_particles.cpp, read_soft.cpp, read_rigid.cpp; the Node helper in
// json_node.h).
// A later module adds its array by adding a row to kSections below and a reader file.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <unordered_map>
#include <utility>
#include <vector>

#include "json_node.h"

namespace pba {

namespace {

using scene_detail::Context;
using scene_detail::json;
using scene_detail::Node;

// Top-level arrays. A later module adds a row (its name and a reader of one item); the
// names below marked "later" are reserved for the modules that will fill them.
struct Section {
  const char* name;
  void (*read)(const Node&, World&);
};
constexpr Section kSections[] = {
    {"particles", scene_detail::read_particle},
    {"emitters", scene_detail::read_emitter},
    {"forcers", scene_detail::read_forcer},
    {"colliders", scene_detail::read_collider},
    {"soft_bodies", scene_detail::read_soft_body},
    {"rigid_bodies", scene_detail::read_rigid_body},
};
constexpr const char* kReserved[] = {"skeletons"};

// 1-based line and column of a byte offset
void line_col(std::string_view text, std::size_t byte, std::size_t& line, std::size_t& col) {
  line = 1;
  col = 1;
  for (std::size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
}

// A key that occurs twice in one object of a syntactically valid JSON text: nlohmann
// keeps the last silently, so the text is scanned for them (strings, nesting, keys with
// their byte offsets and the JSON pointer of their object).
struct DuplicateKey {
  bool found = false;
  std::string key, object;  // the key and the JSON pointer of the object holding it
  std::size_t first = 0, second = 0;  // byte offsets of the two occurrences
};

DuplicateKey find_duplicate_key(std::string_view text) {
  // Linear in the text: a frame holds its own token only (the current member's key or
  // item's index; the pointer of a container is its ancestors' tokens, made when a duplicate
  // is found) and an object its keys by hash. Each frame kept its whole pointer, and each
  // key was compared with every earlier one, before: a file nested n deep took O(n^2) time
  // and memory, an object of n keys O(n^2) time (200,000 brackets: minutes and tens of GB;
  // 40,000 keys: 7 s).
  struct Frame {
    bool object = false;
    bool expect_key = false;
    std::size_t index = 0;  // arrays: the current item
    std::string key;        // objects: the current member's key
    std::unordered_map<std::string, std::size_t> keys;  // objects: keys seen, with offsets
  };
  std::vector<Frame> stack;
  // the pointer of the innermost container ("/" for the root)
  auto pointer = [&] {
    std::string path;
    for (std::size_t k = 0; k + 1 < stack.size(); ++k) {
      const Frame& f = stack[k];
      path += "/" + (f.object ? Node::pointer_token(f.key) : std::to_string(f.index));
    }
    return path.empty() ? std::string("/") : path;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '"') {
      // a string: its raw content, decoded by the JSON parser only if it has escapes
      const std::size_t start = i;
      for (++i; i < text.size() && text[i] != '"'; ++i)
        if (text[i] == '\\') ++i;
      std::string s(text.substr(start + 1, i - start - 1));
      if (stack.empty() || !stack.back().object || !stack.back().expect_key) continue;
      if (s.find('\\') != std::string::npos) s = json::parse(text.substr(start, i - start + 1)).get<std::string>();
      Frame& f = stack.back();
      if (const auto [it, fresh] = f.keys.try_emplace(s, start); !fresh) return {true, s, pointer(), it->second, start};
      f.key = s;
      f.expect_key = false;
    } else if (c == '{' || c == '[') {
      Frame f;
      f.object = c == '{';
      f.expect_key = f.object;
      stack.push_back(std::move(f));
    } else if (c == '}' || c == ']') {
      if (!stack.empty()) stack.pop_back();
    } else if (c == ',' && !stack.empty()) {
      if (stack.back().object)
        stack.back().expect_key = true;
      else
        ++stack.back().index;
    }
  }
  return {};
}

}  // namespace

Scene parse_scene(std::string_view text, std::string_view source) {
  const Context ctx{std::string(source), {}};
  // syntax: report line and column
  json doc;
  try {
    doc = json::parse(text.begin(), text.end());
  } catch (const json::parse_error& e) {
    std::size_t line = 0, col = 0;
    line_col(text, e.byte > 0 ? e.byte - 1 : 0, line, col);
    std::string what = e.what();
    // drop nlohmann's "[json.exception.parse_error.101] parse error at line 1, column 2: "
    const auto colon = what.find(": ");
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw Error(ctx.source + ":" + std::to_string(line) + ":" + std::to_string(col) + ": JSON syntax error: " + what);
  } catch (const json::exception& e) {
    // e.g. a number literal too large for a double: the parser does not say where, so
    // find the literal in the text
    std::string what = e.what();
    const auto close = what.find("] ");
    if (close != std::string::npos) what = what.substr(close + 2);
    std::size_t line = 1, col = 1;
    const auto q0 = what.find('\''), q1 = what.rfind('\'');
    if (q0 != std::string::npos && q1 > q0) {
      const auto at = text.find(what.substr(q0 + 1, q1 - q0 - 1));
      if (at != std::string_view::npos) line_col(text, at, line, col);
    }
    throw Error(ctx.source + ":" + std::to_string(line) + ":" + std::to_string(col) + ": JSON error: " + what +
                " (numbers must be finite doubles)");
  }
  // a key given twice would be read as its last value: refuse it, naming both
  if (const DuplicateKey d = find_duplicate_key(text); d.found) {
    std::size_t line = 0, col = 0, line0 = 0, col0 = 0;
    line_col(text, d.second, line, col);
    line_col(text, d.first, line0, col0);
    throw Error(ctx.source + ":" + std::to_string(line) + ":" + std::to_string(col) + ": duplicate key \"" + d.key +
                "\" in " + d.object + " (first given at line " + std::to_string(line0) + ", column " +
                std::to_string(col0) + ")");
  }
  const Node root(doc, "", ctx);
  root.require_object();
  // the version comes first: a newer file may have fields this reader does not know
  const long long version = root.at("version").integer(1, 1000000);
  if (version > kSceneFormatVersion)
    root.at("version").fail("this build reads scene format version " + std::to_string(kSceneFormatVersion) +
                            ", the file is version " + std::to_string(version));
  // unknown top-level fields, with the reserved ones named as such
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    const std::string& k = it.key();
    if (k == "version" || k == "name" || k == "description" || k == "settings") continue;
    bool known = false;
    for (const Section& s : kSections) known |= k == s.name;
    if (known) continue;
    for (const char* r : kReserved)
      if (k == r) root.at(r).fail("not supported yet by this build (reserved for a later module)");
    std::string list = "version, name, description, settings";
    for (const Section& s : kSections) list += ", " + std::string(s.name);
    root.at(k.c_str()).fail("unknown field (allowed here: " + list + ")");
  }
  // settings, then the world, then every section in a fixed order
  WorldDef def;
  if (root.has("settings")) scene_detail::read_settings(root.at("settings"), def);
  std::string name = root.str("name", "");
  if (name.empty()) name = std::filesystem::path(std::string(source)).stem().string();
  // the World reserves what the settings ask for (settings.rigid.capacity: up to 2^26 bodies,
  // some 36 GB): an Error there (out of memory) is named as the settings'
  const auto make_world = [&] {
    try {
      return World(def);
    } catch (const Error& e) {
      if (!root.has("settings")) throw;
      root.at("settings").fail(e.what());
    }
  };
  Scene scene{name, root.str("description", ""), make_world()};
  for (const Section& s : kSections) {
    if (!root.has(s.name)) continue;
    const Node arr = root.at(s.name);
    arr.require_array();
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const Node item = arr.item(i);
      item.require_object();
      try {
        s.read(item, scene.world);
      } catch (const Error& e) {
        // library validation messages get the item's location if they lack one
        const std::string msg = e.what();
        if (msg.rfind(ctx.source + ": ", 0) == 0) throw;
        throw Error(item.where() + ": " + msg);
      }
    }
  }
  return scene;
}

Scene load_scene(const std::filesystem::path& file) {
  // a directory opens (and reads as empty) on some systems: say what it is
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    throw Error(file.string() + ": is a directory, not a scene file (give the path of a .json file)");
  // read the whole file; a missing or unreadable file is an Error naming it
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(file.string() + ": cannot open scene file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw Error(file.string() + ": cannot read scene file");
  return parse_scene(ss.str(), file.string());
}

}  // namespace pba
