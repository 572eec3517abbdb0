// dw-recorder export --csv: one CSV per topic, each message decoded once into its row — straight
// from the typed message to text (dds/msg_fields.hpp), no JSON in between.
#include <cmath>
#include <array>
#include <atomic>
#include <charconv>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "dds/msg_fields.hpp"
#include "recordings/recordings.hpp"

namespace dw::recordings {

namespace {

// A row's text in a buffer it keeps, numbers formatted in place: appending each formatted number
// to a std::string went through its general replace (6 % of the export, 4 % more in push_back).
class RowText {
public:
    void clear() { n_ = 0; }
    void reserve(std::size_t n) {
        if (buf_.size() < n) buf_.resize(n);
    }
    void put(char c) {
        room(1);
        buf_[n_++] = c;
    }
    void put(std::string_view s) {
        if (s.empty()) return;  // an empty buffer's data() may be null, which memcpy must not get
        room(s.size());
        std::memcpy(buf_.data() + n_, s.data(), s.size());
        n_ += s.size();
    }
    template <class N>
    void number(N v) {
        room(kNumberRoom);
        n_ = static_cast<std::size_t>(std::to_chars(buf_.data() + n_, buf_.data() + buf_.size(), v).ptr - buf_.data());
    }
    std::string_view view() const { return {buf_.data(), n_}; }
    std::size_t size() const { return n_; }
    void truncate(std::size_t n) { n_ = std::min(n, n_); }

private:
    static constexpr std::size_t kNumberRoom = 64;  // the longest number std::to_chars writes, and more
    void room(std::size_t k) {
        if (buf_.size() - n_ < k) [[unlikely]]
            grow(k);
    }
    [[gnu::noinline]] void grow(std::size_t k) { buf_.resize(std::max(2 * buf_.size(), n_ + k)); }
    std::vector<char> buf_;
    std::size_t n_ = 0;
};

// A string CSV-quoted when it holds a separator, a quote or a line break.
void append_string(RowText& line, const std::string& s) {
    if (s.find_first_of(",\"\n\r") == std::string::npos) {
        line.put(s);
        return;
    }
    line.put('"');
    for (char ch : s) line.put(ch == '"' ? std::string_view("\"\"") : std::string_view(&ch, 1));
    line.put('"');
}

template <class T>
void append_value(RowText& line, const T& v) {
    if constexpr (std::is_same_v<T, bool>) line.put(v ? "true" : "false");
    else if constexpr (std::is_enum_v<T>) line.number(static_cast<std::int64_t>(v));
    else if constexpr (std::is_floating_point_v<T>) {
        if (std::isfinite(v)) line.number(v);  // NaN or inf: an empty cell (no value), never "nan"
    } else if constexpr (std::is_arithmetic_v<T>) line.number(v);
    else append_string(line, v);
}

// A message's cells, each after a comma, onto one line; the lengths of its sequences are its
// shape (rows of one shape have the same columns).
struct Cells {
    RowText& line;
    std::vector<std::uint32_t>& shape;
    template <class T>
    void operator()(const char*, const T& v) {
        add(v);
    }
    template <class T>
    void add(const T& v) {
        if constexpr (dds::IsMessage<T>) {
            dds::fields(v, *this);
        } else if constexpr (dds::IsSequence<T>) {
            shape.push_back(static_cast<std::uint32_t>(v.size()));
            for (const auto& e : v) add(e);
        } else {
            line.put(',');
            append_value(line, v);
        }
    }
};

// The same walk for the column names ("a.b", "a[2].c") or the cells one by one.
struct Columns {
    std::vector<std::string>& names;
    std::vector<std::string>& values;
    std::string prefix;
    template <class T>
    void operator()(const char* name, const T& v) {
        add(prefix.empty() ? std::string(name) : prefix + "." + name, v);
    }
    template <class T>
    void add(const std::string& column, const T& v) {
        if constexpr (dds::IsMessage<T>) {
            Columns nested{names, values, column};
            dds::fields(v, nested);
        } else if constexpr (dds::IsSequence<T>) {
            std::size_t i = 0;
            for (const auto& e : v) add(column + "[" + std::to_string(i++) + "]", e);
        } else {
            names.push_back(column);
            RowText text;
            append_value(text, v);
            values.emplace_back(text.view());
        }
    }
};

// One channel's messages, decoded as its type (chosen once, by its schema's name) into a reused
// message and payload.
class RowCodec {
public:
    virtual ~RowCodec() = default;
    // Appends ",cell,cell..." of the message and its shape; false when the bytes do not decode.
    virtual bool cells(std::span<const std::uint8_t> cdr, RowText& line, std::vector<std::uint32_t>& shape) = 0;
    // The last decoded message's columns and cells, one by one.
    virtual void columns(std::vector<std::string>& names, std::vector<std::string>& values) const = 0;
};

template <class T>
class TypedCodec final : public RowCodec {
public:
    bool cells(std::span<const std::uint8_t> cdr, RowText& line, std::vector<std::uint32_t>& shape) override {
        if (!deserialize(cdr, message_)) return false;
        Cells{line, shape}.add(message_);
        return true;
    }
    void columns(std::vector<std::string>& names, std::vector<std::string>& values) const override {
        Columns c{names, values, ""};
        dds::fields(message_, c);
    }

private:
    T message_;
};

std::unique_ptr<RowCodec> codec_for(const std::string& type_name) {
    std::unique_ptr<RowCodec> codec;
    with_type(type_name, [&](const auto& spec) {
        codec = std::make_unique<TypedCodec<typename std::decay_t<decltype(spec)>::type>>();
    });
    return codec;
}

constexpr std::string_view kTimeColumns[] = {"log_time", "publish_time"};

// One topic's CSV, written as its messages are read. Its columns are its first message's; a row
// of another shape (a longer or shorter sequence) is placed by column name, and one that brings
// new columns makes the table "grown": written again in a second read, once every column is
// known. Memory stays bounded by one row, whatever the recording's size.
struct CsvTable {
    std::unique_ptr<RowCodec> codec;
    std::unique_ptr<AtomicFile> out;
    std::string where;  // "<recording>: <topic>", for errors
    std::vector<std::string> columns;
    std::map<std::string, std::size_t> index;         // built at the first row of another shape
    std::optional<std::vector<std::uint32_t>> shape;  // rows of this shape are written as they come
    std::uint64_t rows = 0;
    bool grew = false;
    // Rows not yet handed to the file, written in blocks of AtomicFile::kBlock; a row longer than
    // kRowRoom grows the buffer.
    static constexpr std::size_t kRowRoom = 64 << 10;
    RowText pending;
    std::vector<std::uint32_t> row_shape;

    void write_header() {
        std::string h;
        for (const auto& c : columns) (h += h.empty() ? "" : ",") += c;
        out->write(h + "\n");
    }
    // The last decoded row placed by column name (new columns added at the end).
    std::string placed(const mcap::Message& m) {
        std::vector<std::string> names(std::begin(kTimeColumns), std::end(kTimeColumns));
        std::vector<std::string> values{std::to_string(m.log_time), std::to_string(m.publish_time)};
        codec->columns(names, values);
        if (index.empty())
            for (std::size_t i = 0; i < columns.size(); ++i) index[columns[i]] = i;
        std::vector<std::string> row(columns.size());
        for (std::size_t i = 0; i < names.size(); ++i) {
            auto [it, added] = index.try_emplace(names[i], columns.size());
            if (added) columns.push_back(names[i]), grew = grew || rows > 0;
            if (row.size() <= it->second) row.resize(it->second + 1);
            row[it->second] = std::move(values[i]);
        }
        std::string text;
        for (std::size_t i = 0; i < columns.size(); ++i)
            (text += i ? "," : "") += i < row.size() ? row[i] : std::string();
        return text + "\n";
    }
    void add(const mcap::Message& m) {
        if (rows == 0) pending.reserve(AtomicFile::kBlock + kRowRoom);
        const std::size_t start = pending.size();
        row_shape.clear();
        pending.number(m.log_time);
        pending.put(',');
        pending.number(m.publish_time);
        if (!codec->cells(m.data, pending, row_shape))
            throw InputError(log::cat(where, ": message ", m.sequence, " (", m.data.size(), " bytes) does not decode"));
        if (columns.empty()) {  // the first row: its columns are the file's
            std::vector<std::string> values;
            columns.assign(std::begin(kTimeColumns), std::end(kTimeColumns));
            codec->columns(columns, values);
            shape = row_shape;
        }
        if (rows == 0) write_header();
        if (shape && row_shape == *shape) {
            pending.put('\n');
            if (pending.size() >= AtomicFile::kBlock) flush();
        } else {
            pending.truncate(start);
            const std::string text = placed(m);
            if (!grew) flush(), out->write(text);  // a grown table is written again in the second read
        }
        ++rows;
    }
    void flush() {
        out->write(pending.view());
        pending.clear();
    }
    void commit() {
        flush();
        out->commit();
    }
};

std::string csv_path(const std::string& dir, const mcap::Channel& c) {
    std::string name = topic_suffix(c.topic);
    std::replace(name.begin(), name.end(), '/', '_');
    return (std::filesystem::path(dir) / (name + ".csv")).string();
}

// A message copied out of the reader's buffers, for a worker: which table, the header fields,
// and its bytes (at `offset` in the batch's storage).
struct Handed {
    CsvTable* table;
    mcap::Message m;  // data: empty here, set from the batch's bytes by the worker
    std::size_t offset;
};
struct Batch {
    std::vector<Handed> messages;
    std::vector<std::uint8_t> bytes;
};

// One of the two threads that turn messages into rows (the reader is a third): the tables are
// split between them by channel, so each table is written by one thread. At most kQueued batches
// wait, which bounds memory.
class CsvWorker {
public:
    static constexpr std::size_t kQueued = 4, kBatch = 4096;
    CsvWorker() : thread_([this] { loop(); }) {}
    ~CsvWorker() { join(); }  // after an error elsewhere: what this worker met is dropped
    // A worker that met an error takes no more: the reader stops reading (csv_pass).
    bool failed() const { return failed_.load(); }
    void push(Batch&& b) {
        std::unique_lock lock(mutex_);
        cv_.wait(lock, [&] { return queue_.size() < kQueued || error_; });
        if (error_) return;
        queue_.push_back(std::move(b));
        cv_.notify_all();
    }
    // Waits for every batch to be written; rethrows what a worker threw.
    void finish() {
        join();
        if (auto e = std::exchange(error_, nullptr)) std::rethrow_exception(e);
    }

private:
    void join() {
        {
            std::lock_guard lock(mutex_);
            done_ = true;
            cv_.notify_all();
        }
        if (thread_.joinable()) thread_.join();
    }
    void loop() {
        for (;;) {
            Batch b;
            {
                std::unique_lock lock(mutex_);
                cv_.wait(lock, [&] { return !queue_.empty() || done_; });
                if (queue_.empty()) return;
                b = std::move(queue_.front());
                queue_.pop_front();
                cv_.notify_all();
            }
            try {
                for (auto& h : b.messages) {
                    h.m.data = std::span<const std::uint8_t>(b.bytes).subspan(h.offset, h.m.data.size());
                    h.table->add(h.m);
                }
            } catch (...) {
                std::lock_guard lock(mutex_);
                error_ = std::current_exception();
                failed_ = true;
                cv_.notify_all();
                return;
            }
        }
    }

    std::atomic<bool> failed_{false};
    std::mutex mutex_;
    std::condition_variable cv_;
    std::deque<Batch> queue_;
    bool done_ = false;
    std::exception_ptr error_;
    std::thread thread_;  // last: started once the rest exists
};

// One read of the recording: rows of the tables `wanted` says to write (all on the first read,
// the grown ones on the second). The reader thread reads and checks the file, makes each table
// on its channel's first message, and hands copies of the messages to the table's worker.
void csv_pass(const std::string& path, const std::string& dir, const std::stop_token& stop,
              std::map<std::uint16_t, CsvTable>& tables, const std::function<bool(std::uint16_t)>& wanted) {
    Catalogue l;
    mcap::Handlers h;
    l.watch(h);
    std::array<CsvWorker, 2> workers;
    struct WorkerFailed {};  // stops the read: the worker's own error is rethrown below
    struct Collision {       // two channels of one CSV name: bad input, said after the read stops
        std::string what;
    };
    std::array<Batch, 2> batches;
    auto hand_over = [&](std::size_t w) {
        workers[w].push(std::move(batches[w]));
        batches[w] = {};
    };
    std::uint64_t read = 0;
    h.on_message = [&](const mcap::Message& m) {
        if (++read % kStopCheckEvery == 0) throw_if_stopped(stop, "the export");
        if (!wanted(m.channel_id)) return;
        const mcap::Channel& c = l.channels.at(m.channel_id);
        CsvTable& t = tables[m.channel_id];
        if (!t.codec && !(t.codec = codec_for(l.type_of(c)))) return;  // not a lab type: no CSV
        if (!t.out) {
            const std::string file = csv_path(dir, c);
            for (const auto& [id, other] : tables)
                if (id != m.channel_id && other.out && other.out->path() == file)
                    throw Collision{log::cat(other.where, " and ", c.topic, " would both be written to ",
                                             std::filesystem::path(file).filename().string())};
            t.out = std::make_unique<AtomicFile>(file), t.where = log::cat(path, ": ", c.topic);
        }
        const std::size_t w = m.channel_id % workers.size();
        if (workers[w].failed()) throw WorkerFailed{};
        Batch& b = batches[w];
        b.messages.push_back({&t, m, b.bytes.size()});
        b.bytes.insert(b.bytes.end(), m.data.begin(), m.data.end());
        if (b.messages.size() >= CsvWorker::kBatch) hand_over(w);
    };
    mcap::ReadResult result;
    std::optional<std::string> collision;
    try {
        result = mcap::read_file(path, h);
    } catch (const WorkerFailed&) {
    } catch (const Collision& c) {
        collision = c.what;
    }
    for (std::size_t w = 0; w < workers.size(); ++w) hand_over(w);
    for (auto& w : workers) w.finish();
    if (collision) throw InputError(*collision);
    require_sound(result, path);
}

}  // namespace

void export_csv(const std::string& path, const std::string& out, const std::stop_token& stop) {
    StagedFolder staged(out);  // every topic's CSV appears together, or none
    const std::string& dir = staged.path();
    std::map<std::uint16_t, CsvTable> tables;
    csv_pass(path, dir, stop, tables, [](std::uint16_t) { return true; });
    std::map<std::uint16_t, CsvTable> grown;
    for (auto& [id, t] : tables) {
        if (!t.grew) continue;
        t.out.reset();                  // its first version had too few columns: dropped, written again below
        grown[id].columns = t.columns;  // every column known: each row placed by name
    }
    if (!grown.empty()) csv_pass(path, dir, stop, grown, [&](std::uint16_t id) { return grown.count(id) > 0; });
    for (auto& [id, t] : tables)
        if (t.out && !t.grew) t.commit();
    for (auto& [id, t] : grown)
        if (t.out) t.commit();
    staged.commit();
}

}  // namespace dw::recordings
