// .tlobe files (lobes/tlobe_io.cpp): header, sizes, CRC-32, inflate and the payload.
// With TLOBE_PAYLOAD (tlobe_payload_fuzz) the input is the inflated payload itself, parsed as
// decode_tlobe does once the header and the checksum pass: skeleton, lobe meshes, occupancy.
#include "fuzz_support.hpp"
#include "lobes/tlobe_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view bytes = treelobes::fuzz::as_text(data, size);
    treelobes::fuzz::expect_only_input_errors([&] {
#ifdef TLOBE_PAYLOAD
        treelobes::lobes::decode_tlobe_payload(bytes, "fuzz input");
#else
        treelobes::lobes::decode_tlobe(bytes, "fuzz input");
#endif
    });
    return 0;
}
