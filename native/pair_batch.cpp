// McBatch (pair_batch.h): opening a pass, evaluating the filled lanes, reporting a failed one.
#include "pair_batch.h"

namespace mcdem_shim {

// The batched pair path needs the sub-models of the `tangential history` combination, which
// ContactModel keeps private, and the tangential model's history offset and energy options (the
// batch computes none of them): the private-access idiom of shim.h, checked by the compiler.
struct McNormalTag {
    typedef NormalModel<MC_ADVANCED> McHistoryModel::*type;
    friend type private_member(McNormalTag);
};
template struct PrivateAccess<McNormalTag, &McHistoryModel::normalModel>;
struct McTangentialTag {
    typedef HistoryTangential McHistoryModel::*type;
    friend type private_member(McTangentialTag);
};
template struct PrivateAccess<McTangentialTag, &McHistoryModel::tangentialModel>;
struct ShearOffsetTag {
    typedef int HistoryTangential::*type;
    friend type private_member(ShearOffsetTag);
};
template struct PrivateAccess<ShearOffsetTag, &HistoryTangential::history_offset>;
template <int K>
struct TangentialFlagTag {
    typedef bool HistoryTangential::*type;
    friend type private_member(TangentialFlagTag);
};
template struct PrivateAccess<TangentialFlagTag<0>, &HistoryTangential::heating>;
template struct PrivateAccess<TangentialFlagTag<1>, &HistoryTangential::heating_track>;
template struct PrivateAccess<TangentialFlagTag<2>, &HistoryTangential::elasticpotflag_>;
template struct PrivateAccess<TangentialFlagTag<3>, &HistoryTangential::dissipatedflag_>;

bool McBatch::open(LAMMPS *lmp, McHistoryModel &cmodel, PairGran *pg, bool extra_outputs) {
    HistoryTangential &tm = cmodel.*private_member(McTangentialTag());
    const NormalModel<MC_ADVANCED> &nm = cmodel.*private_member(McNormalTag());
    if (extra_outputs || !nm.batch_eligible() || tm.*private_member(TangentialFlagTag<0>()) ||
        tm.*private_member(TangentialFlagTag<1>()) || tm.*private_member(TangentialFlagTag<2>()) ||
        tm.*private_member(TangentialFlagTag<3>()) || !lmp->atom->sphere_flag || !lmp->atom->rmass ||
        pg->fr_pair() || !pg->computeflag() || !pg->shearupdate() || !pg->listgranhistory ||
        !pg->storeSumDelta())
        return false;
    lmp_ = lmp;
    pg_ = pg;
    model_ = &nm;
    shear_ = tm.*private_member(ShearOffsetTag());
    record_ = cmodel.get_history_offset(kRecordName);
    dnum_ = pg->dnum();
    dt_ = lmp->update->dt;
    return true;
}

// Neighbour entry jj of i (partner j, centre difference del, radius changes dri, drj at this

void McBatch::flush() {
    if (!used_) return;
    if (mcdem_pair_batch_evaluate(&b_, static_cast<size_t>(used_), dt_) != MCDEM_OK)
        lmp_->error->one(FLERR, ("model mc_advanced: " + last_mcdem_error()).c_str());
    Atom *atom = lmp_->atom;
    double **f = atom->f, **torque = atom->torque;
    const int nlocal = atom->nlocal;
    const bool newton_pair = lmp_->force->newton_pair;
    int **flags = pg_->listgranhistory->firstneigh;
    for (int l = 0; l < used_; l++) {
        if (!b_.ok[l]) fail(l);
        const int i = i_[l], j = j_[l];
        double *hist = &pg_->listgranhistory->firstdouble[i][dnum_ * jj_[l]];
        for (int k = 0; k < 3; k++) hist[shear_ + k] = b_.shear[k][l];
        if (flags) flags[i][jj_[l]] |= CONTACT_NORMAL_MODEL | CONTACT_TANGENTIAL_MODEL;
        // The modified radii as the loop and the core form them: original radius + change.
        model_->write_pair_record(&hist[record_], i, j, b_.radius_i[l] + b_.dri[l], b_.radius_j[l] + b_.drj[l],
                                  std::fabs(b_.normal[l]));
        const double F[3] = {b_.force[0][l], b_.force[1][l], b_.force[2][l]};
        const double relax_i = pg_->relax(i);
        for (int k = 0; k < 3; k++) {
            f[i][k] += relax_i * F[k];
            torque[i][k] += relax_i * b_.torque_i[k][l];
        }
        if (newton_pair || j < nlocal) {
            const double relax_j = pg_->relax(j);
            for (int k = 0; k < 3; k++) {
                f[j][k] += relax_j * -F[k];
                torque[j][k] += relax_j * b_.torque_j[k][l];
            }
        }
        if (pg_->evflag)
            pg_->ev_tally_xyz(i, j, nlocal, newton_pair, 0.0, 0.0, F[0], F[1], F[2], b_.d[0][l], b_.d[1][l],
                              b_.d[2][l]);
    }
    used_ = 0;
}

void McBatch::fail(int l) const {
    mcdem_body bi, bj;
    for (int k = 0; k < 3; k++) {
        bi.x[k] = b_.d[k][l];
        bj.x[k] = 0.0;
        bi.v[k] = b_.vr[k][l];
        bj.v[k] = 0.0;
        bi.omega[k] = b_.omega_i[k][l];
        bj.omega[k] = b_.omega_j[k][l];
    }
    bi.radius = b_.radius_i[l];
    bj.radius = b_.radius_j[l];
    bi.mass = b_.mass_i[l];
    bj.mass = b_.mass_j[l];
    const double *hist = &pg_->listgranhistory->firstdouble[i_[l]][dnum_ * jj_[l] + shear_];
    double shear[3] = {hist[0], hist[1], hist[2]};
    mcdem_contact_force out;
    const Atom *atom = lmp_->atom;
    const bool explained =
        mcdem_particle_particle(&model_->pair_coeffs(atom->type[i_[l]], atom->type[j_[l]]), &bi, &bj, b_.dri[l],
                                b_.drj[l], dt_, shear, &out) != MCDEM_OK;
    stop_at_contact(lmp_, i_[l], j_[l], explained ? last_mcdem_error() : std::string("contact force not finite"));
}


}  // namespace mcdem_shim
