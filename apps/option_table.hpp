// One declaration per command-line option. A command adds each of its flags to an OptionTable
// (name, bound variable, help, then CLI11's checks on the returned option); the table declares
// it on the CLI11 subcommand and later reports every flag's resolved value (command line,
// config file or default) as the "options" object of the command's summary, under the flag's
// long name with '_' for '-' (`--mesh-sides` -> "mesh_sides"). So a flag cannot reach --help
// without reaching the summary. Modelled on PDAL's ProgramArgs::add(name, help, variable).
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <charconv>
#include <functional>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace treelobes::cli {

// The summary key of a CLI11 option: its first long name, '-' -> '_'.
std::string summary_key(const CLI::Option& option);

// A value as the summary shows it: floats by their shortest decimal (0.3, not
// 0.30000001192092896), unset optionals as null, vectors as arrays.
template <class T>
nlohmann::json summary_value(const T& value) {
    if constexpr (std::is_same_v<T, float>) {
        char text[32];
        const auto end = std::to_chars(text, text + sizeof text, value).ptr;
        return std::stod(std::string(text, end));
    } else if constexpr (requires {
                             typename T::value_type;
                             value.has_value();
                         }) {
        return value ? summary_value(*value) : nlohmann::json();
    } else if constexpr (requires { value.begin(); } && !std::is_same_v<T, std::string>) {
        nlohmann::json list = nlohmann::json::array();
        for (const auto& item : value) list.push_back(summary_value(item));
        return list;
    } else {
        return value;
    }
}

class OptionTable {
public:
    explicit OptionTable(CLI::App* command) : command_(command) {}
    OptionTable(const OptionTable&) = delete;
    OptionTable& operator=(const OptionTable&) = delete;

    // `--flag VALUE` bound to `variable`; --help shows its default. Chain CLI11's checks on the result.
    template <class T>
    CLI::Option* add(const std::string& flag, T& variable, const std::string& help) {
        CLI::Option* option = command_->add_option(flag, variable, help)->capture_default_str();
        remember(option, [&variable] { return summary_value(variable); });
        return option;
    }

    // A switch. A flag written "--no-x{false}" clears `variable` when given; the summary reports
    // the switch itself (no_x: true when given), as the user wrote it.
    CLI::Option* add_flag(const std::string& flag, bool& variable, const std::string& help);

    // Reports `resolved()` instead of the bound variable: for flags whose effective value is
    // worked out after parsing (a species' β when --beta is not given).
    void report_as(const std::string& flag, std::function<nlohmann::json()> resolved);

    // {"summary_key": resolved value} for every flag of the table.
    nlohmann::json json() const;

private:
    struct Entry {
        const CLI::Option* option;
        std::function<nlohmann::json()> value;
    };
    void remember(const CLI::Option* option, std::function<nlohmann::json()> value);

    CLI::App* command_;
    std::vector<Entry> entries_;
};

}  // namespace treelobes::cli
