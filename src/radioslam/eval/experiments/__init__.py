"""The paper's experiments (Table I, Fig. 5, Fig. 8) and the CRB comparison, as pure computations."""
