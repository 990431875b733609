// Random-access input for binary readers (LAS, LAZ, COPC): a regular file or a memory buffer.
// Every read is checked against the size first, so counts and offsets from a corrupt header can
// never cause a read past the end or a huge allocation; reads are serialised, so chunks may be
// fetched from several threads.
#pragma once

#include "core/error.hpp"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace treelobes {

class InputFile {
public:
    explicit InputFile(const std::filesystem::path& path) : name_(path.string()) {
        namespace fs = std::filesystem;
        std::error_code ec;
        const fs::file_status status = fs::status(path, ec);
        if (ec || !fs::exists(status)) fail("no such file");
        if (fs::is_directory(status)) fail("is a directory, expected a LAS file");
        // FIFOs and devices have no size to check counts against (and may block forever).
        if (!fs::is_regular_file(status)) fail("is not a regular file, expected a LAS file");
        size_ = fs::file_size(path, ec);
        if (ec) fail("cannot determine the file size: " + ec.message());
        in_.open(path, std::ios::binary);
        if (!in_) fail("cannot open for reading (permission denied?)");
    }

    // Reads from `bytes`, which must outlive the InputFile; `name` labels the messages.
    InputFile(std::span<const std::uint8_t> bytes, std::string name)
            : name_(std::move(name)), size_(bytes.size()), memory_(bytes), in_memory_(true) {}

    std::uint64_t size() const { return size_; }
    const std::string& name() const { return name_; }
    [[noreturn]] void fail(const std::string& what) const { throw Error::input(name_, what); }

    void read(std::uint64_t offset, std::size_t count, std::uint8_t* out, std::string_view what) {
        check_range(offset, count, what);
        if (in_memory_) {
            if (count != 0) std::memcpy(out, memory_.data() + offset, count);
            return;
        }
        const std::lock_guard<std::mutex> lock(mutex_);
        in_.clear();
        in_.seekg(static_cast<std::streamoff>(offset));
        in_.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(count));
        if (static_cast<std::size_t>(in_.gcount()) != count)
            fail("read error in the " + std::string(what) + " at byte " + std::to_string(offset));
    }

    std::vector<std::uint8_t> read(std::uint64_t offset, std::size_t count, std::string_view what) {
        check_range(offset, count, what);  // before allocating
        std::vector<std::uint8_t> out(count);
        read(offset, count, out.data(), what);
        return out;
    }

private:
    void check_range(std::uint64_t offset, std::size_t count, std::string_view what) const {
        if (offset > size_ || count > size_ - offset)
            fail("the " + std::string(what) + " (" + std::to_string(count) + " bytes at byte " + std::to_string(offset) +
                 ") runs past the end of the file (" + std::to_string(size_) + " bytes; truncated?)");
    }

    std::string name_;
    std::uint64_t size_ = 0;
    std::span<const std::uint8_t> memory_;
    bool in_memory_ = false;
    std::ifstream in_;
    std::mutex mutex_;
};

}  // namespace treelobes
