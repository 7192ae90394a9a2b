//! A ZUPT filter in a fixed-rate sensor loop, as firmware runs it: the filter is built once,
//! then each IMU sample is one `step` that neither allocates nor panics.
//!
//! Run with `cargo run --example zupt_loop` (prints the estimated gyro bias).
use nalgebra::{UnitQuaternion, Vector3};
use uasnav_core::zupt::{NoDerivative, ZuptConfig, ZuptFilter};
use uasnav_core::NavError;

fn main() -> Result<(), NavError> {
    let dt_s = 0.01; // 100 Hz IMU
    let level = UnitQuaternion::identity(); // body → NED, at rest and level
    let mut filter = ZuptFilter::new(
        ZuptConfig::default(),
        level,
        Vector3::zeros(),
        Vector3::zeros(),
        dt_s,
    )?;
    // A gyro with a constant bias of 0.001 rad/s on z, at rest: specific force −g on z.
    let gyro_rad_s = [0.0, 0.0, 1e-3];
    let accel_m_s2 = [0.0, 0.0, -9.806_65];
    for _ in 0..60_000 {
        // `stationary` comes from the vehicle (landed) or `zupt::detect::StationarityDetector`
        filter.step(&gyro_rad_s, &accel_m_s2, None, true, &mut NoDerivative)?;
    }
    let bg = filter.gyro_bias_rad_s();
    println!(
        "after 600 s at rest: {} updates, gyro bias [{:.2e}, {:.2e}, {:.2e}] rad/s",
        filter.updates(),
        bg.x,
        bg.y,
        bg.z
    );
    Ok(())
}
