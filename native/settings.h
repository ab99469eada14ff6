/*
 * Keywords of `model mc_advanced` that LIGGGHTS's Settings cannot express: one with two named
 * options, and numbers parsed strictly. Registered by normal_model_setup.cpp.
 */
#ifndef MCDEM_SHIM_SETTINGS_H
#define MCDEM_SHIM_SETTINGS_H

#include "shim.h"

namespace mcdem_shim {

// A keyword with two named options (`mprTest abs|signed`, `pairRadii modified|stock`); `given`, if
// not NULL, records that the deck line gave it.
class ChoiceSetting : public Setting {
public:
    ChoiceSetting(const char *name, const char *off, const char *on, bool *target, bool *given)
        : Setting(name, 1), off_(off), on_(on), target_(target), given_(given) {}
    int parseArguments(char **args) {
        if (name != args[0]) return 0;
        const char *v = args[1];
        if (v && (off_ == v || on_ == v)) {
            *target_ = on_ == v;
            if (given_) *given_ = true;
            return 2;
        }
        error_message = "model mc_advanced: " + name + " must be '" + off_ + "' or '" + on_ + "', got '" +
                        (v ? v : "") + "'";
        return -1;
    }
    void print_value(FILE *out) { std::fprintf(out, "%s", (*target_ ? on_ : off_).c_str()); }

private:
    std::string off_, on_;
    bool *target_;
    bool *given_;
};

// Numeric model settings parsed strictly: the library's own DoubleSetting reads with atof, which
// would turn a typo into 0 without a word. Each parser takes the whole word or fails.
inline bool parse_nonnegative(const char *v, double *out) {
    char *end = NULL;
    const double d = std::strtod(v, &end);
    if (end == v || *end != '\0' || !std::isfinite(d) || d < 0.0) return false;
    *out = d;
    return true;
}

inline bool parse_step_count(const char *v, int *out) {
    char *end = NULL;
    const long k = std::strtol(v, &end, 10);
    if (end == v || *end != '\0' || k < 1 || k > 1000000000L) return false;
    *out = static_cast<int>(k);
    return true;
}

inline void print_setting(FILE *out, double v) { std::fprintf(out, "%g", v); }
inline void print_setting(FILE *out, int v) { std::fprintf(out, "%d", v); }

// `geometryTolerance 1e-3` (a number >= 0), `updateEvery 10` (a whole number of steps >= 1).
template <typename T, bool (*Parse)(const char *, T *)>
class StrictSetting : public Setting {
public:
    StrictSetting(const char *name, T *target, bool *given, const char *expected)
        : Setting(name, 1), target_(target), given_(given), expected_(expected) {}
    int parseArguments(char **args) {
        if (name != args[0]) return 0;
        const char *v = args[1];
        if (!v || !Parse(v, target_)) {
            error_message = "model mc_advanced: " + name + " must be " + expected_ + ", got '" + (v ? v : "") + "'";
            return -1;
        }
        *given_ = true;
        return 2;
    }
    void print_value(FILE *out) { print_setting(out, *target_); }

private:
    T *target_;
    bool *given_;
    std::string expected_;
};

// A keyword of `mcdem run`'s model mc_advanced that the plugin does not implement (`mcAccuracy`,
// `mcAccuracyCheck`): stops the deck with a message naming it, rather than LIGGGHTS's generic
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
