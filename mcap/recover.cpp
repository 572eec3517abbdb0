// Recovery: a salvaging read of a damaged file into a new, whole one.
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>

#include "mcap/records.hpp"

namespace dw::mcap {

ReadResult recover(const std::string& in_path, const std::string& out_path, const WriterOptions& options,
                   const std::stop_token& stop) {
    detail::require_magic(in_path, "nothing to recover");  // the input is checked before any output exists
    const std::string tmp = log::cat(out_path, ".tmp-", ::getpid());
    try {
        Writer out(tmp, options);
        std::map<std::uint16_t, std::uint16_t> schema_ids, channel_ids;
        Handlers h;
        h.on_schema = [&](const Schema& s) { schema_ids[s.id] = out.add_schema(s.name, s.encoding, s.data); };
        h.on_channel = [&](const Channel& c) {
            const auto schema = schema_ids.find(c.schema_id);
            channel_ids[c.id] = out.add_channel(c.topic, schema == schema_ids.end() ? 0 : schema->second,
                                                c.message_encoding, c.metadata);
        };
        h.on_message = [&](const Message& m) {
            Message copy = m;
            copy.channel_id = channel_ids.at(m.channel_id);  // the reader hands on only messages of known channels
            out.write(copy, 0);
        };
        h.on_metadata = [&](const Metadata& m) { out.add_metadata(m); };
        h.on_attachment = [&](const Attachment& a) { out.add_attachment(a); };
        h.on_progress = [&](std::uint64_t, std::uint64_t) {
            if (stop.stop_requested()) throw Stopped("the recovery");
        };
        const ReadResult r = read_file(in_path, h, ReadMode::salvage);
        out.close();
        if (::rename(tmp.c_str(), out_path.c_str()) != 0)
            throw RuntimeError(log::cat("cannot write ", out_path, ": ", std::strerror(errno)));
        return r;
    } catch (...) {
        ::unlink(tmp.c_str());
        throw;
    }
}

}  // namespace dw::mcap
