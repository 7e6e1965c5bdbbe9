#include "cvephands_bridge/room/room_protocol.h"

#include <chrono>
#include <cmath>
#include <cstring>

#include "room_json.h"

namespace cvephands {
namespace room {
namespace {

void putLe(uint8_t* p, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) p[i] = uint8_t(v >> (8 * i));
}
uint64_t getLe(const uint8_t* p, int bytes) {
  uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

const json::Value* member(const json::Value& v, std::string_view key, json::Value::Type type) {
  const json::Value* m = v.find(key);
  return m && m->type == type ? m : nullptr;
}

bool asInt(const json::Value* v, int64_t lo, int64_t hi, int64_t* out) {
  if (!v || !v->isNumber() || v->number != std::floor(v->number)) return false;
  if (v->number < double(lo) || v->number > double(hi)) return false;
  *out = int64_t(v->number);
  return true;
}

bool parseRole(std::string_view s, Role* role) {
  if (s == "rig")
    *role = Role::kRig;
  else if (s == "viewer")
    *role = Role::kViewer;
  else
    return false;
  return true;
}

// seat_pose: 16 numbers, or null (identity).
bool parsePose(const json::Value* v, SeatPose* pose) {
  *pose = identityPose();
  if (!v || v->isNull()) return true;
  if (!v->isArray() || v->array.size() != 16) return false;
  for (size_t i = 0; i < 16; ++i) {
    if (!v->array[i].isNumber()) return false;
    (*pose)[i] = v->array[i].number;
  }
  return true;
}

// A welcome names the id "participant", a participants entry "id".
bool parseParticipant(const json::Value& v, const char* id_key, ParticipantInfo* p) {
  int64_t id, seat;
  const json::Value* name = member(v, "name", json::Value::Type::kString);
  const json::Value* role = member(v, "role", json::Value::Type::kString);
  if (!asInt(v.find(id_key), 0, UINT32_MAX, &id) || !asInt(v.find("seat"), -1, INT32_MAX, &seat) ||
      !name || !role || !parseRole(role->string, &p->role) ||
      !parsePose(v.find("seat_pose"), &p->seat_pose))
    return false;
  p->id = uint32_t(id);
  p->seat = int(seat);
  p->name = name->string;
  return true;
}

void appendPose(std::string* out, const ParticipantInfo& p) {
  if (p.role == Role::kViewer) {
    out->append("null");
    return;
  }
  out->push_back('[');
  for (size_t i = 0; i < 16; ++i) {
    if (i) out->push_back(',');
    json::appendNumber(out, p.seat_pose[i]);
  }
  out->push_back(']');
}

// The members a welcome and a participants entry share.
void appendParticipantFields(std::string* out, const ParticipantInfo& p, const char* id_key) {
  out->append("\"");
  out->append(id_key);
  out->append("\":");
  json::appendInteger(out, p.id);
  out->append(",\"name\":");
  json::appendString(out, p.name);
  out->append(",\"role\":");
  json::appendString(out, roleName(p.role));
  out->append(",\"seat\":");
  json::appendInteger(out, p.seat);
  out->append(",\"seat_pose\":");
  appendPose(out, p);
}

// The "id" member of a ping / pong as JSON text ("null" when absent); false when it is there
// but neither a number nor a string.
bool pingId(const json::Value& v, std::string* out) {
  *out = "null";
  const json::Value* id = v.find("id");
  if (!id) return true;
  out->clear();
  if (id->isNumber())
    json::appendNumber(out, id->number);
  else if (id->isString())
    json::appendString(out, id->string);
  else
    return false;
  return true;
}

ClientMessage invalid(const char* reason, std::string detail) {
  ClientMessage m;
  m.type = ClientMessage::Type::kInvalid;
  m.reason = reason;
  m.detail = std::move(detail);
  return m;
}

}  // namespace

void writeRelayHeader(const RelayHeader& h, uint8_t out[kRelayHeaderSize]) {
  std::memset(out, 0, kRelayHeaderSize);
  std::memcpy(out, kRelayMagic, 4);
  out[4] = kRelayVersion;
  out[5] = uint8_t(kRelayHeaderSize);
  putLe(out + 8, h.sender, 4);
  putLe(out + 12, h.seat, 4);
  putLe(out + 16, h.sequence, 4);
  putLe(out + 24, h.server_time_us, 8);
}

bool readRelayHeader(const uint8_t* data, size_t size, RelayHeader* h, size_t* payload_offset) {
  if (size < kRelayHeaderSize || std::memcmp(data, kRelayMagic, 4) != 0 ||
      data[4] != kRelayVersion || data[5] < kRelayHeaderSize || data[5] > size)
    return false;
  h->sender = uint32_t(getLe(data + 8, 4));
  h->seat = uint32_t(getLe(data + 12, 4));
  h->sequence = uint32_t(getLe(data + 16, 4));
  h->server_time_us = getLe(data + 24, 8);
  *payload_offset = data[5];
  return true;
}

SeatPose identityPose() {
  SeatPose t{};
  t[0] = t[5] = t[10] = t[15] = 1.0;
  return t;
}

SeatPose seatPose(int seat, const SeatLayout& layout) {
  const double a = 2.0 * M_PI * seat / layout.seats;
  const double c = std::cos(a), s = std::sin(a);
  SeatPose t = identityPose();
  // Columns: images of world x, y, z, then the translation.
  t[0] = -s, t[1] = c, t[2] = 0;
  t[4] = -c, t[5] = -s, t[6] = 0;
  t[8] = 0, t[9] = 0, t[10] = 1;
  t[12] = layout.radius * c, t[13] = layout.radius * s, t[14] = 0;
  return t;
}

const char* roleName(Role role) { return role == Role::kViewer ? "viewer" : "rig"; }

bool validRoomName(std::string_view room) {
  if (room.empty() || room.size() > kMaxRoomLength) return false;
  for (const char c : room)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
          c == '.' || c == '-'))
      return false;
  return true;
}

ClientMessage parseClientMessage(std::string_view text) {
  json::Value v;
  std::string error;
  if (!json::parse(text, &v, &error)) return invalid("malformed", "invalid JSON: " + error);
  const json::Value* type = member(v, "type", json::Value::Type::kString);
  if (!type) return invalid("malformed", "expected a JSON object with a string \"type\"");

  ClientMessage m;
  if (type->string == "join") {
    const json::Value* room = member(v, "room", json::Value::Type::kString);
    if (!room || !validRoomName(room->string))
      return invalid("bad_join", "\"room\" must be 1..64 characters of [A-Za-z0-9_.-]");
    m.join.room = room->string;
    if (const json::Value* name = v.find("name")) {
      if (!name->isString() || name->string.size() > kMaxNameLength)
        return invalid("bad_join", "\"name\" must be a string of at most 64 bytes");
      m.join.name = name->string;
    }
    if (const json::Value* token = v.find("token")) {
      if (!token->isString()) return invalid("bad_join", "\"token\" must be a string");
      m.join.token = token->string;
    }
    if (const json::Value* role = v.find("role")) {
      if (!role->isString() || !parseRole(role->string, &m.join.role))
        return invalid("bad_join", "\"role\" must be \"rig\" or \"viewer\"");
    }
    m.type = ClientMessage::Type::kJoin;
    return m;
  }
  if (type->string == "ping") {
    if (!pingId(v, &m.ping_id))
      return invalid("malformed", "ping \"id\" must be a number or a string");
    m.type = ClientMessage::Type::kPing;
    return m;
  }
  return invalid("unknown_type", "unknown message type");
}

ServerMessage parseServerMessage(std::string_view text) {
  ServerMessage m;
  json::Value v;
  std::string error;
  if (!json::parse(text, &v, &error)) {
    m.detail = "invalid JSON: " + error;
    return m;
  }
  const json::Value* type = member(v, "type", json::Value::Type::kString);
  if (!type) {
    m.detail = "no \"type\"";
    return m;
  }
  const json::Value* room = member(v, "room", json::Value::Type::kString);
  if (room) m.room = room->string;
  int64_t time_us = 0;
  if (asInt(v.find("server_time_us"), 0, int64_t(1) << 53, &time_us)) m.server_time_us = time_us;

  if (type->string == "welcome") {
    int64_t seats;
    if (!room || !asInt(v.find("seats"), 1, INT32_MAX, &seats) ||
        !parseParticipant(v, "participant", &m.self)) {
      m.detail = "bad welcome";
      return m;
    }
    m.seats = int(seats);
    m.type = ServerMessage::Type::kWelcome;
  } else if (type->string == "participants") {
    const json::Value* list = member(v, "list", json::Value::Type::kArray);
    if (!room || !list) {
      m.detail = "bad participants";
      return m;
    }
    for (const json::Value& e : list->array) {
      ParticipantInfo p;
      if (!parseParticipant(e, "id", &p)) {
        m.detail = "bad participants entry";
        m.participants.clear();
        return m;
      }
      m.participants.push_back(std::move(p));
    }
    m.type = ServerMessage::Type::kParticipants;
  } else if (type->string == "pong") {
    pingId(v, &m.ping_id);  // an id of another type is left empty (the server never sends one)
    m.type = ServerMessage::Type::kPong;
  } else if (type->string == "error") {
    const json::Value* reason = member(v, "reason", json::Value::Type::kString);
    const json::Value* detail = member(v, "detail", json::Value::Type::kString);
    m.reason = reason ? reason->string : "unknown";
    if (detail) m.detail = detail->string;
    m.type = ServerMessage::Type::kError;
  } else {
    m.detail = "unknown type " + type->string;
  }
  return m;
}

std::string encodeJoin(const JoinRequest& join) {
  std::string s = "{\"type\":\"join\",\"room\":";
  json::appendString(&s, join.room);
  s += ",\"name\":";
  json::appendString(&s, join.name);
  if (!join.token.empty()) {
    s += ",\"token\":";
    json::appendString(&s, join.token);
  }
  s += ",\"role\":";
  json::appendString(&s, roleName(join.role));
  s += '}';
  return s;
}

std::string encodePing(std::string_view id_json) {
  std::string s = "{\"type\":\"ping\",\"id\":";
  s += id_json;
  s += '}';
  return s;
}

std::string encodeWelcome(const std::string& room, const ParticipantInfo& self, int seats,
                          uint64_t server_time_us) {
  std::string s = "{\"type\":\"welcome\",\"protocol\":";
  json::appendInteger(&s, kProtocolVersion);
  s += ",\"room\":";
  json::appendString(&s, room);
  s += ',';
  appendParticipantFields(&s, self, "participant");
  s += ",\"seats\":";
  json::appendInteger(&s, seats);
  s += ",\"server_time_us\":";
  json::appendInteger(&s, int64_t(server_time_us));
  s += '}';
  return s;
}

std::string encodeParticipants(const std::string& room, const std::vector<ParticipantInfo>& list) {
  std::string s = "{\"type\":\"participants\",\"room\":";
  json::appendString(&s, room);
  s += ",\"list\":[";
  for (size_t i = 0; i < list.size(); ++i) {
    if (i) s += ',';
    s += '{';
    appendParticipantFields(&s, list[i], "id");
    s += '}';
  }
  s += "]}";
  return s;
}

std::string encodePong(std::string_view id_json, uint64_t server_time_us) {
  std::string s = "{\"type\":\"pong\",\"id\":";
  s += id_json;
  s += ",\"server_time_us\":";
  json::appendInteger(&s, int64_t(server_time_us));
  s += '}';
  return s;
}

std::string encodeError(std::string_view reason, std::string_view detail) {
  std::string s = "{\"type\":\"error\",\"reason\":";
  json::appendString(&s, reason);
  s += ",\"detail\":";
  json::appendString(&s, detail);
  s += '}';
  return s;
}

uint64_t nowMicros() {
  return uint64_t(std::chrono::duration_cast<std::chrono::microseconds>(
                      std::chrono::system_clock::now().time_since_epoch())
                      .count());
}

}  // namespace room
}  // namespace cvephands
