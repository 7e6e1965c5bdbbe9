// The rooms: joining (seats), leaving, relaying hand messages to the others, and the stats.
#include <algorithm>

#include "room_server_internal.h"

namespace cvephands {
namespace room_server_internal {

void ServerCore::countKick(const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++kicked_[reason];
}

Bytes ServerCore::participantsMessage(const std::string& name, const Room& r) const {
  std::vector<room::ParticipantInfo> list;
  for (const auto& m : r.members) {
    room::ParticipantInfo p;
    p.id = m->id;
    p.name = m->name;
    p.role = m->role;
    p.seat = m->seat;
    if (m->seat >= 0) p.seat_pose = room::seatPose(m->seat, options_.seats);
    list.push_back(std::move(p));
  }
  return std::make_shared<const std::string>(room::encodeParticipants(name, list));
}

bool ServerCore::join(const std::shared_ptr<WsSession>& s, const room::JoinRequest& request,
                      Bytes* welcome, Bytes* list, std::string* reason, std::string* detail) {
  room::ParticipantInfo self;
  std::vector<std::shared_ptr<WsSession>> others;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto reg = connections_.find(s.get());
    if (reg == connections_.end()) {  // not registered: the server is stopping
      *reason = "shutdown";
      *detail = "the server is stopping";
      return false;
    }
    if (joined_ >= options_.max_clients) {
      *reason = "server_full";
      *detail = "the server has its maximum of " + std::to_string(options_.max_clients) + " participants";
      return false;
    }
    Room& r = rooms_[request.room];
    if (r.seat_taken.empty()) r.seat_taken.assign(options_.seats.seats, false);
    int seat = -1;
    if (request.role == room::Role::kRig) {
      const auto free = std::find(r.seat_taken.begin(), r.seat_taken.end(), false);
      if (free == r.seat_taken.end()) {
        if (r.members.empty()) rooms_.erase(request.room);
        *reason = "room_full";
        *detail = "all " + std::to_string(options_.seats.seats) + " seats of the room are taken";
        return false;
      }
      seat = int(free - r.seat_taken.begin());
      *free = true;
    }
    s->id = next_id_++;
    s->room = request.room;
    s->name = request.name.empty() ? "participant " + std::to_string(s->id) : request.name;
    s->role = request.role;
    s->seat = seat;
    unpendLocked(reg->second);
    reg->second.joined = true;
    ++joined_;
    r.members.push_back(s);  // ids only grow: stays sorted
    r.snapshot = std::make_shared<const std::vector<std::shared_ptr<WsSession>>>(r.members);
    self.id = s->id;
    self.name = s->name;
    self.role = s->role;
    self.seat = seat;
    if (seat >= 0) self.seat_pose = room::seatPose(seat, options_.seats);
    *list = participantsMessage(request.room, r);
    for (const auto& m : r.members)
      if (m != s) others.push_back(m);
  }
  *welcome = std::make_shared<const std::string>(
      room::encodeWelcome(request.room, self, options_.seats.seats, room::nowMicros()));
  for (const auto& m : others) m->deliver(*list, false);
  return true;
}

void ServerCore::leave(WsSession* s) {
  Bytes list;
  std::vector<std::shared_ptr<WsSession>> rest;
  std::shared_ptr<WsSession> keep;  // released outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = rooms_.find(s->room);
    if (it == rooms_.end()) return;
    Room& r = it->second;
    const auto m = std::find_if(r.members.begin(), r.members.end(),
                                [s](const std::shared_ptr<WsSession>& p) { return p.get() == s; });
    if (m == r.members.end()) return;
    keep = std::move(*m);
    r.members.erase(m);
    if (s->seat >= 0) r.seat_taken[s->seat] = false;
    r.departed.add(*s);
    if (r.members.empty()) {
      rooms_.erase(it);
    } else {
      r.snapshot = std::make_shared<const std::vector<std::shared_ptr<WsSession>>>(r.members);
      list = participantsMessage(s->room, r);
      rest = r.members;
    }
  }
  for (const auto& m : rest) m->deliver(list, false);
}

void ServerCore::relay(WsSession& sender, const beast::flat_buffer& payload) {
  const size_t n = payload.size();
  auto message = std::make_shared<std::string>(room::kRelayHeaderSize + n, '\0');
  room::RelayHeader h;
  h.sender = sender.id;
  h.seat = uint32_t(sender.seat);
  h.sequence = sender.sequence++;
  h.server_time_us = room::nowMicros();
  room::writeRelayHeader(h, reinterpret_cast<uint8_t*>(&(*message)[0]));
  net::buffer_copy(net::buffer(&(*message)[room::kRelayHeaderSize], n), payload.data());
  ++sender.messages_in;
  sender.bytes_in += n;
  std::shared_ptr<const std::vector<std::shared_ptr<WsSession>>> members;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = rooms_.find(sender.room);
    if (it == rooms_.end()) return;
    members = it->second.snapshot;
  }
  const Bytes shared = std::move(message);
  for (const auto& m : *members)
    if (m.get() != &sender) m->deliver(shared, true);
}

RoomServerStats ServerCore::stats() const {
  RoomServerStats st;
  st.connections = connections;
  st.http_requests = http_requests;
  st.dropped = dropped;
  st.rate_dropped = rate_dropped;
  std::lock_guard<std::mutex> lock(mutex_);
  st.kicked = kicked_;
  st.pending = pending_[1];
  for (const auto& [name, r] : rooms_) {
    RoomStats rs;
    rs.name = name;
    Totals t = r.departed;
    for (const auto& m : r.members) {
      (m->role == room::Role::kViewer ? rs.viewers : rs.rigs)++;
      t.add(*m);
      ParticipantStats p;
      p.id = m->id;
      p.room = name;
      p.name = m->name;
      p.role = m->role;
      p.seat = m->seat;
      p.messages_in = m->messages_in;
      p.bytes_in = m->bytes_in;
      p.messages_out = m->messages_out;
      p.bytes_out = m->bytes_out;
      p.dropped = m->dropped;
      p.rate_dropped = m->rate_dropped;
      p.queued = m->queued;
      st.participants.push_back(std::move(p));
    }
    rs.messages_in = t.messages_in, rs.bytes_in = t.bytes_in, rs.messages_out = t.messages_out;
    rs.bytes_out = t.bytes_out, rs.dropped = t.dropped;
    st.rooms.push_back(std::move(rs));
  }
  std::sort(st.participants.begin(), st.participants.end(),
            [](const ParticipantStats& a, const ParticipantStats& b) { return a.id < b.id; });
  return st;
}

}  // namespace room_server_internal
}  // namespace cvephands
