/*
 * NormalModel<MC_ADVANCED>'s set-up: the per-contact record, the keywords of the deck line, the
 * material table (validated by the core) and the checks that walls and pair agree.
 */
#include "normal_model.h"
#include "settings.h"

namespace mcdem_shim {

// The keywords of settings.h are not on/off, yes/no or plain double keywords, the only ones
// Settings offers publicly: they go into its private table.
struct SettingsTableTag {
    typedef std::map<std::string, Setting *> Settings::*type;
    friend type private_member(SettingsTableTag);
};
template struct PrivateAccess<SettingsTableTag, &Settings::settings>;

}  // namespace mcdem_shim

namespace LIGGGHTS {
namespace ContactModels {

NormalModel<MC_ADVANCED>::NormalModel(LAMMPS *lmp, IContactHistorySetup *hsetup, ContactModelBase *c)
    : NormalModelBase(lmp, hsetup, c),
      cmb_(c),
      record_offset_(-1),
      tangential_damping_(true),
      limit_force_(false),
      signed_test_(false),
      stock_pair_radii_(false),
      geometry_tolerance_(0.0),
      update_every_(1),
      last_update_(-1),
      cache_(NULL),
      ntypes_(0),
      sources_ready_(false) {
    for (int k = 0; k < MCDEM_SETTINGS; k++) {
        settings_[k] = mcdem_setting_default(k);
        given_[k] = false;
    }
    // Per-contact record read by the next step's radius changes: pairs the two modified radii
    // (see write_pair_record) and |F_n|; walls the contact point relative to the centre and
    // |F_n| (the layout LIGGGHTS's HistoryData expects).
    if (c->is_wall()) {
        record_offset_ = hsetup->add_history_value("mcdem_point_x", "0");
        hsetup->add_history_value("mcdem_point_y", "0");
        hsetup->add_history_value("mcdem_point_z", "0");
        hsetup->add_history_value("mcdem_fn", "0");
    } else {
        record_offset_ = hsetup->add_history_value("mcdem_radius_lo", "0");
        hsetup->add_history_value("mcdem_radius_hi", "0");
        hsetup->add_history_value("mcdem_fn", "0");
        // This step's radius changes of both partners at this contact (see copy_to_pair_records),
        // read by the pair loop (mc_pair_loop) without searching the per-atom store.
        hsetup->add_history_value("mcdem_dr_lo", "0");
        hsetup->add_history_value("mcdem_dr_hi", "0");
    }
    c->add_history_offset(kRecordName, record_offset_);
}

NormalModel<MC_ADVANCED>::~NormalModel() {
    std::map<LAMMPS *, NormalModel *>::iterator it = pair_models_.find(lmp);
    if (it != pair_models_.end() && it->second == this) pair_models_.erase(it);
    mcdem_influence_cache_free(cache_);
}

void NormalModel<MC_ADVANCED>::registerSettings(Settings &settings) {
    settings.registerOnOff("tangential_damping", tangential_damping_, true);
    settings.registerOnOff("limitForce", limit_force_);
    std::map<std::string, Setting *> &table = settings.*private_member(SettingsTableTag());
    for (int k = 0; k < MCDEM_SETTINGS; k++) {
        const char *name = mcdem_setting_name(k);
        if (table.find(name) == table.end()) table[name] = new CoreSetting(k, &settings_[k], &given_[k]);
    }
    // Keywords only `mcdem run` implements (the library's list and reason).
    for (int k = 0; const char *key = mcdem_engine_only_setting(k); k++)
        if (table.find(key) == table.end()) table[key] = new UnsupportedSetting(key, mcdem_engine_only_why());
}

void NormalModel<MC_ADVANCED>::postSettings(IContactHistorySetup *, ContactModelBase *) {
    signed_test_ = settings_[MCDEM_SETTING_MPR_TEST] != 0.0;
    stock_pair_radii_ = settings_[MCDEM_SETTING_PAIR_RADII] != 0.0;
    geometry_tolerance_ = settings_[MCDEM_SETTING_GEOMETRY_TOLERANCE];
    update_every_ = static_cast<int>(settings_[MCDEM_SETTING_UPDATE_EVERY]);
    if (cmb_->is_wall()) return;
    pair_models_[lmp] = this;
    // Switches on the library's per-contact radius storage, read by the pair and wall loops
    // for detection, overlap and effective radius; it must be set before the pair's init.
    PairGran *pg = dynamic_cast<PairGran *>(force->pair);
    if (!pg) error->all(FLERR, "model mc_advanced: the pair style is not a granular pair style");
    pg->do_store_multicontact_data();
}

void NormalModel<MC_ADVANCED>::connectToProperties(PropertyRegistry &) {
    read_materials();
    if (cmb_->is_wall()) {
        PairGran *pg = static_cast<PairGran *>(force->pair_match("gran", 0));
        if (!pg || !pg->contact_match("normal", "mc_advanced"))
            error->all(FLERR, "fix wall/gran with model mc_advanced needs `pair_style gran model mc_advanced`: "
                              "the multi-contact radius changes are computed by the pair style");
        check_wall_settings();
        return;
    }
    if (force->newton_pair)
        error->all(FLERR, "model mc_advanced needs `newton off` (per-contact data are stored on both partners)");
    neighbor->register_contact_dist_factor(kContactDistanceFactor);
    if (mcdem_pair_batch_size() != sizeof(mcdem_pair_batch))
        error->all(FLERR, "model mc_advanced: native/mcdem.h and the mcdem library disagree on the size of "
                          "mcdem_pair_batch (rebuild both from one checkout)");
    // Walls must see the same radius changes as pairs: give every granular wall its store now,
    // during the pair's init, so that the fixes created here are initialised with the others.
    const int nwalls = modify->n_fixes_style("wall/gran");
    for (int w = 0; w < nwalls; w++) {
        FixWallGran *fwg = static_cast<FixWallGran *>(modify->find_fix_style("wall/gran", w));
        if (!fwg->contact_match("normal", "mc_advanced")) {
            char msg[256];
            std::snprintf(msg, sizeof(msg),
                          "fix %s: walls must use `model mc_advanced` when the pair style does "
                          "(a wall contact deforms the particle at its other contacts)",
                          fwg->id);
            error->all(FLERR, msg);
        }
        if (fwg->is_mesh_wall()) {
            for (int m = 0; m < fwg->n_meshes(); m++) fwg->mesh_list()[m]->createMulticontactData();
        } else {
            fwg->createMulticontactData();
        }
    }
    sources_ready_ = false;
}

// Stops a deck whose wall gives a setting of the pair style's multi-contact pass another value
// than the pair style's, instead of ignoring it (the library decides which and says so).
void NormalModel<MC_ADVANCED>::check_wall_settings() const {
    std::map<LAMMPS *, NormalModel *>::const_iterator it = pair_models_.find(lmp);
    if (it == pair_models_.end()) return;
    uint8_t given[MCDEM_SETTINGS];
    for (int k = 0; k < MCDEM_SETTINGS; k++) given[k] = given_[k];
    if (mcdem_settings_check_wall(settings_, given, it->second->settings_) != MCDEM_OK)
        error->all(FLERR, last_mcdem_error().c_str());
}

FixPropertyGlobal *NormalModel<MC_ADVANCED>::find_property(const char *name, const char *kind, int len, const char *usage) {
    Fix *f = modify->find_fix_property(name, "property/global", kind, len, 0, "model mc_advanced", false);
    if (!f) {
        char msg[512];
        std::snprintf(msg, sizeof(msg),
                      "model mc_advanced needs property %s: add `fix ID all property/global %s %s` %s",
                      name, name, kind, usage);
        error->all(FLERR, msg);
    }
    return static_cast<FixPropertyGlobal *>(f);
}

// Reads the material per atom type, validates it through the core and builds the pair
// coefficient table (one entry per type pair, walls have their own atom type).
void NormalModel<MC_ADVANCED>::read_materials() {
    const int n = atom->get_properties()->max_type();
    char usage[64];
    std::snprintf(usage, sizeof(usage), "(%d values, one per atom type)", n);
    char usage_pair[64];
    std::snprintf(usage_pair, sizeof(usage_pair), "%d followed by %d values", n, n * n);
    const double *E = find_property("youngsModulus", "peratomtype", n, usage)->get_values();
    const double *nu = find_property("poissonsRatio", "peratomtype", n, usage)->get_values();
    const double *gamma = find_property("geometricPrefactor", "peratomtype", n, usage)->get_values();
    const double *mpr = find_property("maxPenetrationRatio", "peratomtype", n, usage)->get_values();
    FixPropertyGlobal *rest = find_property("coefficientRestitution", "peratomtypepair", n, usage_pair);
    Fix *fric_fix = modify->find_fix_property("coefficientFriction", "property/global", "peratomtypepair", n, n,
                                              "model mc_advanced", false);
    FixPropertyGlobal *fric = static_cast<FixPropertyGlobal *>(fric_fix);

    // The library validates the values and builds the table (one builder for both engines).
    std::vector<double> r(n * n), mu(n * n, 0.0);
    for (int a = 0; a < n; a++) {
        for (int b = 0; b < n; b++) {
            r[a * n + b] = rest->compute_array(a, b);
            if (fric) mu[a * n + b] = fric->compute_array(a, b);
        }
    }
    std::vector<mcdem_mc_params> params(n);
    std::vector<mcdem_pair_coeffs> coeffs(n * n);
    if (mcdem_material_table(n, E, nu, gamma, mpr, signed_test_ ? MCDEM_CAP_SIGNED : MCDEM_CAP_ABS, &r[0], &mu[0],
                             &params[0], &coeffs[0]) != MCDEM_OK)
        error->all(FLERR, ("model mc_advanced: " + last_mcdem_error()).c_str());
    // Atom types count from 1 in LIGGGHTS: the shim's tables keep an unused row 0.
    ntypes_ = n;
    params_.assign(n + 1, mcdem_mc_params());
    coeffs_.assign(n + 1, std::vector<mcdem_pair_coeffs>(n + 1));
    for (int a = 1; a <= n; a++) {
        params_[a] = params[a - 1];
        for (int b = 1; b <= n; b++) coeffs_[a][b] = coeffs[(a - 1) * n + (b - 1)];
    }
}

std::map<LAMMPS *, NormalModel<MC_ADVANCED> *> NormalModel<MC_ADVANCED>::pair_models_;

}  // namespace ContactModels
}  // namespace LIGGGHTS
