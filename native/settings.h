/*
 * The keywords of `model mc_advanced` that LIGGGHTS's Settings cannot express. Their names,
 * defaults, strict parsing and messages are the library's (mcdem_setting_*, one table shared with
 * `mcdem run`'s deck reader): the shim only hands the words over. Registered by
 * normal_model_setup.cpp.
 */
#ifndef MCDEM_SHIM_SETTINGS_H
#define MCDEM_SHIM_SETTINGS_H

#include "shim.h"

namespace mcdem_shim {

// Setting k of the library's table; `given` records that the deck line gave it.
class CoreSetting : public Setting {
public:
    CoreSetting(int k, double *value, bool *given)
        : Setting(mcdem_setting_name(k), 1), k_(k), value_(value), given_(given) {}
    int parseArguments(char **args) {
        if (name != args[0]) return 0;
        // A missing word reads as '' so that the library's message names it.
        if (mcdem_setting_parse(k_, args[1] ? args[1] : "", value_) != MCDEM_OK) {
            error_message = "model mc_advanced: " + last_mcdem_error();
            return -1;
        }
        *given_ = true;
        return 2;
    }
    void print_value(FILE *out) { std::fprintf(out, "%g", *value_); }

private:
    int k_;
    double *value_;
    bool *given_;
};

// A keyword of `mcdem run`'s model mc_advanced that the plugin does not implement (the library's
// list, mcdem_engine_only_setting): stops the deck with a message naming it, rather than LIGGGHTS's generic
// unknown-keyword error or, worse, running without the setting.
class UnsupportedSetting : public Setting {
public:
    UnsupportedSetting(const char *name, const char *why) : Setting(name, 1), why_(why) {}
    int parseArguments(char **args) {
        if (name != args[0]) return 0;
        error_message = "model mc_advanced: " + name + " is not implemented in the LIGGGHTS plugin (" + why_ + ")";
        return -1;
    }
    void print_value(FILE *out) { std::fprintf(out, "-"); }

private:
    std::string why_;
};

}  // namespace mcdem_shim

#endif
