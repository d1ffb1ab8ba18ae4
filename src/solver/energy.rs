//! Energy bookkeeping of a run: what went in, where it is, and the balance.

/// Energies at one instant (N·mm = mJ).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energies {
    /// `1/2 sum m v^2`.
    pub kinetic: f64,
    /// Work of the internal forces, `sum f_int . du`: stored plus dissipated.
    pub internal_work: f64,
    /// Elastic energy stored in the laminate, `sum_e A0 sum_k t_k W_k` (at output instants).
    pub elastic: f64,
    /// Work of the reaction forces at the constrained nodes and of the tools' contact forces
    /// on the blank: what the machine put in.
    pub external_work: f64,
    /// The tools' part of `external_work` (contact and friction forces on the blank).
    pub tool_work: f64,
    /// Gravity's, the springs' and the grippers' part of `external_work`.
    pub support_work: f64,
    /// Energy removed by the global mass-proportional damping.
    pub damping: f64,
    /// Energy taken by the yarn-rate damping (part of the internal work).
    pub numerical_damping: f64,
    /// Work of the plies' contact and friction forces on one another, `sum f . du` over every
    /// node: minus what the film dissipated and the contact springs hold; 0 for one ply.
    pub interply_work: f64,
}

impl Energies {
    /// Energy dissipated by the matrix viscosity: internal work neither stored elastically nor
    /// taken by the yarn-rate damping.
    pub fn viscous_dissipation(&self) -> f64 {
        self.internal_work - self.elastic - self.numerical_damping
    }

    /// `W_ext + W_ply - W_int - E_kin - W_damp`: zero for an exact integration.
    pub fn balance(&self) -> f64 {
        self.external_work + self.interply_work - self.internal_work - self.kinetic - self.damping
    }

    /// The balance relative to the external work (0 when nothing was put in yet).
    pub fn balance_error(&self) -> f64 {
        if self.external_work.abs() > 0.0 {
            self.balance().abs() / self.external_work.abs()
        } else {
            0.0
        }
    }
}
