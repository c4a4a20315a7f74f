//! Batched inference of small multilayer perceptrons (dense layers, tanh or linear).
