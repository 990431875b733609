// The parametric L-system parser (lsystem/lsystem_parser.cpp): #define, axiom, productions with
// conditions, probabilities and expressions; a system that parses is also derived (with a small
// module budget, which the derivation must respect) and interpreted by the turtle.
#include "fuzz_support.hpp"
#include "lsystem/lsystem.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace treelobes::lsystem;
    treelobes::fuzz::expect_only_input_errors([&] {
        const LSystem system = parse_lsystem(treelobes::fuzz::as_text(data, size), "fuzz input");
        DeriveOptions options;
        options.max_modules = 20000;
        const ModuleString string = derive(system, options);
        interpret(apply_homomorphism(system, string, options));
    });
    return 0;
}
