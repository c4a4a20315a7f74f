//! Foot contacts (Lee et al. 2002) with a temporal-continuity filter.
