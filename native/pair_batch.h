/*
 * McBatch: the overlapping pairs of one force pass handed to the core eight at a time
 * (pair_batch.cpp). Used by the pair loop (pair_loop.cpp).
 */
#ifndef MCDEM_SHIM_PAIR_BATCH_H
#define MCDEM_SHIM_PAIR_BATCH_H

#include "pair_loop.h"

namespace mcdem_shim {

typedef TangentialModel<TANGENTIAL_HISTORY> HistoryTangential;

// The pair batch of one force pass: overlapping pairs gathered lane by lane into the core's
// mcdem_pair_batch, evaluated eight at a time by mcdem_pair_batch_evaluate (the same contact as the
// one-contact path: Hertz normal force on the modified radii, damping, history tangential force),
// and their forces, torques, tangential histories and records written back. Used where the batch
// computes exactly what the sub-models would (see McBatch::open); every other pair takes the
// one-contact path.
class McBatch {
public:
    McBatch() : model_(NULL), used_(0) { std::memset(&b_, 0, sizeof(b_)); }

    // Ready for a pass of the history model when its settings and the pass's outputs allow it.
    bool open(LAMMPS *lmp, McHistoryModel &cmodel, PairGran *pg, bool extra_outputs);

    // Neighbour entry jj of i (partner j, centre difference del, radius changes dri, drj at this
    // contact) into the next lane.
    void push(int i, int j, int jj, const double *del, double dri, double drj) {
        const Atom *atom = lmp_->atom;
        const int l = used_;
        double **v = atom->v, **omega = atom->omega;
        const double *hist = &pg_->listgranhistory->firstdouble[i][dnum_ * jj + shear_];
        for (int k = 0; k < 3; k++) {
            b_.d[k][l] = del[k];
            b_.vr[k][l] = v[i][k] - v[j][k];
            b_.omega_i[k][l] = omega[i][k];
            b_.omega_j[k][l] = omega[j][k];
            b_.shear[k][l] = hist[k];
        }
        b_.radius_i[l] = atom->radius[i];
        b_.radius_j[l] = atom->radius[j];
        b_.dri[l] = dri;
        b_.drj[l] = drj;
        b_.mass_i[l] = atom->rmass[i];
        b_.mass_j[l] = atom->rmass[j];
        const mcdem_pair_coeffs &c = model_->pair_coeffs(atom->type[i], atom->type[j]);
        b_.e_star[l] = c.e_star;
        b_.g_star[l] = c.g_star;
        b_.beta[l] = c.beta;
        b_.friction[l] = c.friction;
        b_.damping_ratio_t_n[l] = c.damping_ratio_t_n;
        i_[l] = i;
        j_[l] = j;
        jj_[l] = jj;
        if (++used_ == MCDEM_BATCH_LANES) flush();
    }

    // Evaluates the lanes filled so far and writes their results where the sub-models would.
    void flush();

private:
    // Stops the run at a lane the core could not integrate, with the core's reason for that pair.
    void fail(int l) const;

    mcdem_pair_batch b_;
    LAMMPS *lmp_;
    PairGran *pg_;
    const NormalModel<MC_ADVANCED> *model_;
    int shear_, record_, dnum_;
    double dt_;
    int used_;
    int i_[MCDEM_BATCH_LANES], j_[MCDEM_BATCH_LANES], jj_[MCDEM_BATCH_LANES];
};

// The batch serves the `tangential history` combination; `no_history` keeps the one-contact path.
template <typename Model>
bool open_batch(McBatch &, LAMMPS *, Model &, PairGran *, bool) {
    return false;
}
template <>
inline bool open_batch(McBatch &batch, LAMMPS *lmp, McHistoryModel &cmodel, PairGran *pg, bool extra_outputs) {
    return batch.open(lmp, cmodel, pg, extra_outputs);
}

}  // namespace mcdem_shim

#endif
