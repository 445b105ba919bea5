//! The flipped sign conventions of a D-H joint put back into the nominal
//! arm's.

use super::*;

/// Puts `params` into the sign convention of `nominal` where the fit left a
/// joint in the equivalent flipped form, returning the names changed.
///
/// `Rot_z(θ+π)·Trans_z(d)·Trans_x(−a)·Rot_x(−α)` equals
/// `Rot_z(θ)·Trans_z(d)·Trans_x(a)·Rot_x(α)·Rot_z(π)`: joint `i` with
/// `θ_i + π`, `−a_i`, `−α_i` leaves a half turn about the next `z` axis,
/// which the next zero offset absorbs (`θ_{i+1} + π`), or which passes
/// through the next joint by negating its `a` and `α`, or reaches the probe
/// as `(−Bx, −By)`. Only free parameters (`free`, columns) are changed, so a
/// fixed one keeps its value; probe positions are unchanged.
pub(crate) fn normalize_signs(
    params: &mut DhParams,
    nominal: &DhParams,
    free: &[usize],
) -> Vec<String> {
    let n = params.joint_count();
    let id = |kind, index| ParamId { kind, index };
    let is_free = |p: ParamId| free.contains(&p.column(n));
    let reach = nominal.reach();
    let mut changed = Vec::new();
    for i in 0..n {
        let (a, al) = (params.joints[i].a, params.joints[i].alpha);
        let (na, nal) = (nominal.joints[i].a, nominal.joints[i].alpha);
        let dist =
            |a: f64, al: f64| ((a - na) / reach).powi(2) + crate::params::wrap(al - nal).powi(2);
        if dist(-a, -al) >= dist(a, al) {
            continue;
        }
        // The half turn to absorb: find where, through free parameters only.
        // A Hayati joint's Ry(β) turns with its twist: Rz(π) carries
        // through Tx(a)·Rx(α)·Ry(β) as Tx(−a)·Rx(−α)·Ry(−β).
        let hayati_beta = |j: usize| {
            (params.joints[j].model == crate::params::JointModel::Hayati)
                .then(|| id(ParamKind::Beta, j))
        };
        let mut plan = vec![
            id(ParamKind::Theta, i),
            id(ParamKind::A, i),
            id(ParamKind::Alpha, i),
        ];
        plan.extend(hayati_beta(i));
        let mut absorbed = false;
        for j in i + 1..n {
            if is_free(id(ParamKind::Theta, j)) {
                plan.push(id(ParamKind::Theta, j));
                absorbed = true;
                break;
            }
            plan.extend([id(ParamKind::A, j), id(ParamKind::Alpha, j)]);
            plan.extend(hayati_beta(j));
        }
        if !absorbed {
            plan.extend([id(ParamKind::Probe, 0), id(ParamKind::Probe, 1)]);
        }
        let zero = |p: &ParamId| p.kind != ParamKind::Theta && params.get(*p) == 0.0;
        if !plan.iter().all(|p| is_free(*p) || zero(p)) {
            // The half turn cannot pass the last joint by negating its twist
            // (held fixed): it passes as `−a_n` and a half turn of the probe
            // about `Rx(−α_n)·z`, when the parameters that moves are free.
            if !absorbed {
                last_joint_route(params, i, free, &mut changed);
            }
            continue;
        }
        for p in plan {
            let v = params.get_mut(p);
            if p.kind == ParamKind::Theta {
                *v = crate::params::wrap(*v + std::f64::consts::PI);
            } else if *v != 0.0 {
                *v = -*v;
            } else {
                continue;
            }
            changed.push(p.to_string());
        }
    }
    changed
}

/// The flip of joint `i` (`θ_i + π`, `−a_i`, `−α_i`) with its half turn
/// carried through the joints after it by negating their `a` and `α` up to
/// the last joint, and through the last joint as `−a_n` with the probe
/// turned by π about `Rx(−α_n)·z` (`Rz(π)·Tx(a)·Rx(α)·B = Tx(−a)·Rx(α)·
/// R_u(π)·B`). Applied, and the names changed appended to `changed`, only
/// when every value it changes is free (or zero and stays zero).
fn last_joint_route(
    params: &mut DhParams,
    i: usize,
    free: &[usize],
    changed: &mut Vec<String>,
) -> bool {
    let n = params.joint_count();
    // Not derived for Hayati links (their Ry(β) sits between Rx(α) and the
    // probe): their sign convention is left as the fit found it.
    if params.joints[i..]
        .iter()
        .any(|j| j.model == crate::params::JointModel::Hayati)
    {
        return false;
    }
    let id = |kind, index| ParamId { kind, index };
    let is_free = |p: ParamId| free.contains(&p.column(n));
    let mut negate = vec![id(ParamKind::A, i), id(ParamKind::Alpha, i)];
    for j in i + 1..n - 1 {
        negate.extend([id(ParamKind::A, j), id(ParamKind::Alpha, j)]);
    }
    negate.push(id(ParamKind::A, n - 1));
    let alpha = params.joints[n - 1].alpha;
    let u = [0.0, alpha.sin(), alpha.cos()];
    let b = params.probe;
    let ub: f64 = (0..3).map(|k| u[k] * b[k]).sum();
    let turned: [f64; 3] = std::array::from_fn(|k| 2.0 * ub * u[k] - b[k]);
    let probe_ok = (0..3).all(|k| {
        is_free(id(ParamKind::Probe, k)) || (turned[k] - b[k]).abs() <= 1e-12 * b[k].abs().max(1.0)
    });
    let theta = id(ParamKind::Theta, i);
    let ok =
        is_free(theta) && probe_ok && negate.iter().all(|&p| is_free(p) || params.get(p) == 0.0);
    if !ok {
        return false;
    }
    let t = params.get_mut(theta);
    *t = crate::params::wrap(*t + std::f64::consts::PI);
    changed.push(theta.to_string());
    for p in negate {
        let v = params.get_mut(p);
        if *v != 0.0 {
            *v = -*v;
            changed.push(p.to_string());
        }
    }
    for (k, v) in turned.into_iter().enumerate() {
        if params.probe[k] != v {
            params.probe[k] = v;
            changed.push(id(ParamKind::Probe, k).to_string());
        }
    }
    true
}
