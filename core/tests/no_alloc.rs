//! The annealer's inner loop allocates nothing: preparing a kernel from a
//! parameter set edited in place and evaluating the energy, counted by
//! `allocation-counter` (whose global allocator this test binary alone
//! links).

use aacmm_core::calibrate::energy::Energy;
use aacmm_core::domain::Arm;
use aacmm_core::kernel::ArmKernel;
use aacmm_core::params::{DhParams, ParamId};
use aacmm_core::simulate::{CampaignSettings, ErrorModel, simulate};

#[test]
fn energy_evaluations_allocate_nothing() {
    let nominal = Arm::without_limits("n", DhParams::paper_nominal());
    let campaign = simulate(&nominal, &CampaignSettings::new(2, ErrorModel::Paper, 6, 8)).unwrap();
    let data = campaign.data_set().unwrap();
    let mut energy = Energy::new(&data);
    let mut params = nominal.params.clone();
    let ids: Vec<ParamId> = ParamId::all(6).collect();
    let mut total = 0.0;
    let info = allocation_counter::measure(|| {
        for step in 0..1000 {
            *params.get_mut(ids[step % ids.len()]) += 1e-6;
            let kernel = ArmKernel::new(&params).unwrap();
            total += energy.of_kernel(&kernel, &data);
        }
    });
    assert!(total.is_finite() && total > 0.0);
    assert_eq!(
        info.count_total, 0,
        "allocations in 1000 energy evaluations"
    );
}
