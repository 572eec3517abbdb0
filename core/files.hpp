#pragma once
// Reading and writing whole files the one house way: an input that is missing, a directory or
// unreadable is one clear dw::InputError; an output is written to a temporary file beside it,
// checked, and renamed into place, so a failure (full disk, unwritable folder, a stop request)
// leaves no half-written file behind.
#include <filesystem>
#include <string>
#include <string_view>

namespace dw {

// The bytes of a regular file. `what` names the input in the error ("--config", "meta.json").
std::string read_file(const std::string& path, std::string_view what);
// The bytes of a file the lab wrote itself (a child's log, a report it just made): the same read,
// but a failure is the lab's, a dw::RuntimeError (exit 1), not bad input.
std::string read_file(const std::string& path);
// Whether anything is at `path`, a dangling or looping symbolic link included: an optional input
// that is present is read (and refused if broken), never skipped.
bool present(const std::string& path);
// What is at an input `path` (following symbolic links; not_found when nothing is): a path the
// system cannot resolve (a symbolic link loop, a path through a file, no permission to look) is one
// dw::InputError naming `what` and the path, never the filesystem library's text (exit 1).
std::filesystem::file_status input_status(const std::string& path, std::string_view what);
// Throws dw::InputError unless `path` is an existing regular file that can be opened for reading.
void require_readable_file(const std::string& path, std::string_view what);

// Throws dw::InputError when something other than a regular file or a symbolic link is at `path`
// (a FIFO, a device node, a socket): an output replaces only a file (as root, `--out /dev/null`
// would have replaced the device; a FIFO held the writer past SIGINT). Nothing there is fine.
void require_replaceable(const std::string& path, std::string_view what);

// Writes `content` to `path` atomically (temporary + rename), making missing folders. Throws
// dw::RuntimeError naming the path and the system's reason; no file is left at `path` or beside
// it on failure.
// `mode`: the file's permissions from its creation on (0600 for a private key).
void write_file(const std::string& path, std::string_view content, unsigned mode = 0644);
// A file written piece by piece with write_file's promise: it appears at `path` (renamed from a
// temporary beside it) only when commit() succeeds; destroyed before that, it leaves nothing.
// Throws dw::RuntimeError naming the path and the system's reason.
class AtomicFile {
public:
    explicit AtomicFile(std::string path, unsigned mode = 0644);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    // Writes of fewer than this many bytes are gathered in a buffer; larger ones go straight to the file.
    static constexpr std::size_t kBlock = 1 << 20;
    void write(std::string_view bytes);
    void commit();
    const std::string& path() const { return path_; }

private:
    void flush();
    void write_through(std::string_view bytes);
    void fail(int err);

    std::string path_, tmp_;
    int fd_ = -1;
    std::string buffer_;
};

// A multi-file output (a flight folder, a report, a keystore) whole or not at all: its files are
// written under path() (a staging folder inside `dir`, .staging-<pid>) and moved into `dir` by
// commit(), each by a rename. Destroyed before commit() (an error, a stop), it removes the staging
// folder, and `dir` too when it made it (with the parents it made for it). Throws dw::RuntimeError naming the folder.
class StagedFolder {
public:
    explicit StagedFolder(const std::string& dir);
    ~StagedFolder();
    StagedFolder(const StagedFolder&) = delete;
    StagedFolder& operator=(const StagedFolder&) = delete;

    const std::string& path() const { return staging_; }
    const std::string& dir() const { return dir_; }
    void commit();

private:
    std::string dir_, staging_, made_top_;
    bool made_dir_ = false, committed_ = false;
};

// Throws dw::InputError when `path` cannot become a file: it is empty or a directory, or its
// folder does not exist; dw::RuntimeError (exit 1) when the folder exists but cannot be written
// (a read-only file system, permissions). Creates nothing: for checking an output option before
// long work starts.
void require_writable_path(const std::string& path, std::string_view what);
// The same for an output folder: `path` may exist as a directory or be made; creates nothing.
void require_output_dir(const std::string& path, std::string_view what);

// Letters, digits, '_', '-' and '.', not starting with '.': a name that can be a file name (a
// process's log, a keystore identity's folder) and never a path.
bool is_plain_name(std::string_view name);

}  // namespace dw
