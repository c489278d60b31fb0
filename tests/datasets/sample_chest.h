// The chest the scan simulator's tests scan: subject 11 of the default population, a typical chest with a
// moderate depression (the same in every test that scans one, so their figures compare).
#pragma once

#include "datasets/chest_population.h"
#include "datasets/chest_surface.h"

namespace pectus::datasets {

inline ChestSurface SampleChest() {
  return ChestSurface(SampleSubject(PopulationModel::Default(), 11).parameters);
}

}  // namespace pectus::datasets
