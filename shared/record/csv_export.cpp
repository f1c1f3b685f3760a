#include "shared/record/csv_export.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <set>
#include <stdexcept>
#include <vector>

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>

#include "shared/record/mcap_reader.hpp"

namespace inspect::record {
namespace {

namespace pb = google::protobuf;
using RepeatCounts = std::map<std::string, int>;  // field path without indexes ("a.b") -> largest size seen

struct Step {  // into a sub-message: the field and, when repeated, the element
  const pb::FieldDescriptor* field;
  int index;  // -1 when not repeated
};

struct Column {
  std::string name;
  std::vector<Step> path;  // message fields from the top message to the leaf's
  const pb::FieldDescriptor* leaf;
  int index;  // -1 when not repeated
};

// Largest size of every repeated field, nested ones included, in `counts`.
void countRepeated(const pb::Message& m, const std::string& key, RepeatCounts& counts) {
  const pb::Descriptor* d = m.GetDescriptor();
  const pb::Reflection* r = m.GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const pb::FieldDescriptor* f = d->field(i);
    const std::string k = key + f->name();
    const bool message = f->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE;
    if (f->is_repeated()) {
      const int n = r->FieldSize(m, f);
      int& most = counts[k];
      most = std::max(most, n);
      for (int j = 0; message && j < n; ++j) countRepeated(r->GetRepeatedMessage(m, f, j), k + ".", counts);
    } else if (message && r->HasField(m, f)) {
      countRepeated(r->GetMessage(m, f), k + ".", counts);
    }
  }
}

struct ColumnBuilder {
  const RepeatCounts& counts;
  bool include_bytes;
  std::vector<Column> out;
  std::vector<Step> path;
  std::vector<const pb::Descriptor*> open;  // types being expanded (recursion guard)

  void add(const pb::Descriptor* d, const std::string& prefix, const std::string& key) {
    open.push_back(d);
    for (int i = 0; i < d->field_count(); ++i) {
      const pb::FieldDescriptor* f = d->field(i);
      const bool bytes = f->type() == pb::FieldDescriptor::TYPE_BYTES;
      const bool message = f->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE;
      if ((bytes && !include_bytes) || (message && std::ranges::count(open, f->message_type()) > 0)) continue;
      const std::string name = prefix + f->name() + (bytes ? "_bytes" : "");
      const std::string k = key + f->name();
      const auto n = f->is_repeated() ? counts.find(k) : counts.end();
      const int first = f->is_repeated() ? 0 : -1;
      const int end = f->is_repeated() ? (n == counts.end() ? 0 : n->second) : 0;
      for (int j = first; j < end; ++j) {  // once for a singular field, `end` times for a repeated one
        const std::string label = j < 0 ? name : name + "[" + std::to_string(j) + "]";
        if (message) {
          path.push_back({f, j});
          add(f->message_type(), label + ".", k + ".");
          path.pop_back();
        } else {
          out.push_back({label, path, f, j});
        }
      }
    }
    open.pop_back();
  }
};

template <class T>
std::string number(T v) {
  char buf[40];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);  // shortest exact form for floating point
  return std::string(buf, ec == std::errc() ? end : buf);
}

std::string csvField(std::string_view s) {
  if (s.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(s);
  std::string q = "\"";
  for (const char c : s) q.append(c == '"' ? 2 : 1, c);
  return q + "\"";
}

// ns since the epoch as exact decimal seconds.
std::string seconds(uint64_t ns) {
  std::string frac = std::to_string(ns % 1'000'000'000);
  return std::to_string(ns / 1'000'000'000) + "." + std::string(9 - frac.size(), '0') + frac;
}

// The value of a scalar field (element `i` when repeated) as a CSV cell.
std::string cell(const pb::Message& m, const pb::FieldDescriptor* f, int i) {
  const pb::Reflection* r = m.GetReflection();
  auto get = [&](auto single, auto repeated) { return i < 0 ? (r->*single)(m, f) : (r->*repeated)(m, f, i); };
  using R = pb::Reflection;
  switch (f->cpp_type()) {
    case pb::FieldDescriptor::CPPTYPE_INT32: return number(get(&R::GetInt32, &R::GetRepeatedInt32));
    case pb::FieldDescriptor::CPPTYPE_INT64: return number(get(&R::GetInt64, &R::GetRepeatedInt64));
    case pb::FieldDescriptor::CPPTYPE_UINT32: return number(get(&R::GetUInt32, &R::GetRepeatedUInt32));
    case pb::FieldDescriptor::CPPTYPE_UINT64: return number(get(&R::GetUInt64, &R::GetRepeatedUInt64));
    case pb::FieldDescriptor::CPPTYPE_DOUBLE: return number(get(&R::GetDouble, &R::GetRepeatedDouble));
    case pb::FieldDescriptor::CPPTYPE_FLOAT: return number(get(&R::GetFloat, &R::GetRepeatedFloat));
    case pb::FieldDescriptor::CPPTYPE_BOOL: return get(&R::GetBool, &R::GetRepeatedBool) ? "true" : "false";
    case pb::FieldDescriptor::CPPTYPE_ENUM: {
      const int v = get(&R::GetEnumValue, &R::GetRepeatedEnumValue);
      const pb::EnumValueDescriptor* e = f->enum_type()->FindValueByNumber(v);
      return e ? e->name() : number(v);
    }
    case pb::FieldDescriptor::CPPTYPE_STRING: {
      std::string scratch;
      const std::string& s =
          i < 0 ? r->GetStringReference(m, f, &scratch) : r->GetRepeatedStringReference(m, f, i, &scratch);
      return f->type() == pb::FieldDescriptor::TYPE_BYTES ? number(s.size()) : csvField(s);
    }
    case pb::FieldDescriptor::CPPTYPE_MESSAGE: break;  // never a leaf
  }
  return {};
}

// The cell of column `c` in message `top`; empty when a message on its path,
// the element, or a field with presence is absent.
std::string cell(const pb::Message& top, const Column& c) {
  const pb::Message* m = &top;
  const auto absent = [&](const pb::FieldDescriptor* f, int i) {
    const pb::Reflection* r = m->GetReflection();
    return i < 0 ? f->has_presence() && !r->HasField(*m, f) : i >= r->FieldSize(*m, f);
  };
  for (const Step& s : c.path) {
    if (absent(s.field, s.index)) return {};
    const pb::Reflection* r = m->GetReflection();
    m = s.index < 0 ? &r->GetMessage(*m, s.field) : &r->GetRepeatedMessage(*m, s.field, s.index);
  }
  return absent(c.leaf, c.index) ? std::string() : cell(*m, c.leaf, c.index);
}

struct CsvFile {
  std::string path;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f{nullptr, &std::fclose};
  std::vector<Column> columns;
  uint64_t rows = 0;

  void line(const std::vector<std::string>& cells) {
    std::string s;
    for (const std::string& c : cells) (s += c) += ',';
    s.back() = '\n';
    if (std::fwrite(s.data(), 1, s.size(), f.get()) != s.size()) fail("cannot write");
  }
  void close() {
    if (std::fclose(f.release()) != 0) fail("cannot write");
  }
  [[noreturn]] void fail(const char* what) const {
    throw std::runtime_error(std::string("csv: ") + what + " " + path + ": " + std::strerror(errno));
  }
};

std::string fileBase(std::string_view topic, std::string_view drop_prefix) {
  if (!drop_prefix.empty() && topic.starts_with(drop_prefix) && topic.size() > drop_prefix.size())
    topic.remove_prefix(drop_prefix.size());
  if (topic.starts_with('/')) topic.remove_prefix(1);
  std::string name(topic);
  std::ranges::replace(name, '/', '_');
  return name;
}

/// The 3-D scene's channels (docs/foxglove.md) are drawings of what the other
/// channels hold (walls, beams, rings; pixels of the gas maps; the telemetry's
/// people as boxes on the camera image): no table.
bool drawing(const pb::Descriptor* d) {
  if (!d) return false;
  const std::string& n = d->full_name();
  return n == "foxglove.SceneUpdate" || n == "foxglove.FrameTransforms" || n == "foxglove.Grid" ||
         n == "foxglove.ImageAnnotations";
}

}  // namespace

CsvExportResult exportCsv(const std::string& mcap_path, const std::string& out_dir, bool include_bytes,
                          std::string_view drop_prefix) {
  const McapReader reader = McapReader::open(mcap_path);
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw std::runtime_error("csv: cannot create " + out_dir + ": " + ec.message());

  // Pass 1: the largest size of every repeated field, per channel.
  std::map<uint16_t, RepeatCounts> counts;
  reader.forEach([&](const McapMessageView& v) {
    const pb::Descriptor* d = reader.descriptor(v.channel_id);
    if (d && !drawing(d)) countRepeated(*reader.decode(v), "", counts[v.channel_id]);
    return true;
  });

  CsvExportResult result;
  std::map<uint16_t, CsvFile> files;
  std::set<std::string> names;
  for (const auto& [id, ch] : reader.channels()) {
    if (drawing(reader.descriptor(id))) continue;
    std::string base = fileBase(ch.topic, drop_prefix);
    if (base.empty() || !names.insert(base).second) base += "_" + std::to_string(id);
    names.insert(base);
    CsvFile& out = files[id];
    out.path = (std::filesystem::path(out_dir) / (base + ".csv")).string();
    out.f.reset(std::fopen(out.path.c_str(), "w"));
    if (!out.f) out.fail("cannot create");
    if (const pb::Descriptor* d = reader.descriptor(id)) {
      ColumnBuilder b{counts[id], include_bytes, {}, {}, {}};
      b.add(d, "", "");
      out.columns = std::move(b.out);
    }
    std::vector<std::string> header{"log_time_s", "publish_time_s"};
    for (const Column& c : out.columns) header.push_back(c.name);
    out.line(header);
  }

  // Pass 2: the rows.
  reader.forEach([&](const McapMessageView& v) {
    const auto it = files.find(v.channel_id);
    if (it == files.end()) return true;  // a message of an undeclared channel
    CsvFile& out = it->second;
    std::vector<std::string> cells{seconds(v.log_time_ns), seconds(v.publish_time_ns)};
    if (!out.columns.empty()) {
      const auto m = reader.decode(v);
      for (const Column& c : out.columns) cells.push_back(cell(*m, c));
    }
    out.line(cells);
    ++out.rows;
    return true;
  });

  for (auto& [id, out] : files) {
    out.close();
    std::string key = reader.channels().at(id).topic;
    if (result.files.contains(key)) key += "#" + std::to_string(id);
    result.files[key] = out.path;
    result.rows[key] = out.rows;
  }
  return result;
}

}  // namespace inspect::record
