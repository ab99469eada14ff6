/*
 * The contact-model instances of `model mc_advanced` and their pair loop (pair_loop.cpp), which
 * replaces the library's generic one. Every file that instantiates those pair styles
 * (registration.cpp) must see these declarations.
 */
#ifndef MCDEM_SHIM_PAIR_LOOP_H
#define MCDEM_SHIM_PAIR_LOOP_H

#include "normal_model.h"

namespace mcdem_shim {

typedef ContactModel<GranStyle<MC_ADVANCED, TANGENTIAL_HISTORY, COHESION_OFF, ROLLING_OFF, SURFACE_DEFAULT> >
    McHistoryModel;
typedef ContactModel<GranStyle<MC_ADVANCED, TANGENTIAL_NO_HISTORY, COHESION_OFF, ROLLING_OFF, SURFACE_DEFAULT> >
    McNoHistoryModel;

}  // namespace mcdem_shim

namespace LIGGGHTS {
namespace PairStyles {

template <>
void Granular<McHistoryModel>::compute_force(PairGran *pg, int eflag, int vflag, int addflag);
template <>
void Granular<McNoHistoryModel>::compute_force(PairGran *pg, int eflag, int vflag, int addflag);

}  // namespace PairStyles
}  // namespace LIGGGHTS

#endif
