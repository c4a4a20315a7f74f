//! Per-joint algebra of decoupling: expressive component, activity index, filtering, recomposition.
