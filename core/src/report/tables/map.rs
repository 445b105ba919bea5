//! The uncertainty map's table: the predicted radius per band of distance
//! from the shoulder.

use super::{Cell, table};
use crate::plan::UncertaintyMap;

/// The uncertainty map's bands of distance from the shoulder (from, to,
/// poses, RMS and largest 95 % radius), then every pose together (with the
/// median); `json` is the map's pointer.
pub(crate) fn uncertainty_map(map: &UncertaintyMap, json: Option<&str>) -> String {
    let mut rows: Vec<(String, Vec<Cell>)> = (map.regions.iter().enumerate())
        .map(|(i, r)| {
            let at = |field: &str| format!("regions/{i}/{field}");
            let cells = vec![
                Cell::num(r.reach_from_mm, 0).at(json, &at("reach_from_mm"), r.reach_from_mm),
                Cell::num(r.reach_to_mm, 0).at(json, &at("reach_to_mm"), r.reach_to_mm),
                Cell::int(r.poses).at(json, &at("poses"), r.poses as f64),
                Cell::num(r.rms_mm, 4).at(json, &at("rms_mm"), r.rms_mm),
                Cell::none(),
                Cell::num(r.max_mm, 4).at(json, &at("max_mm"), r.max_mm),
            ];
            (String::new(), cells)
        })
        .collect();
    rows.push((
        "after".to_string(),
        vec![
            Cell::text("all poses"),
            Cell::text(""),
            Cell::int(map.poses).at(json, "poses", map.poses as f64),
            Cell::num(map.rms_mm, 4).at(json, "rms_mm", map.rms_mm),
            Cell::num(map.median_mm, 4).at(json, "median_mm", map.median_mm),
            Cell::num(map.max_mm, 4).at(json, "max_mm", map.max_mm),
        ],
    ));
    let head = [
        "from [mm]",
        "to [mm]",
        "poses",
        "RMS [mm]",
        "median [mm]",
        "max [mm]",
    ];
    let mut caption = format!(
        "{:.0} % radius per band of distance from the shoulder",
        100.0 * map.coverage
    );
    if let Some(name) = &map.frame {
        caption += &format!(", in frame `{name}`, its registration included");
    }
    table(&caption, &head, &rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::map::Region;
    use crate::report::tables::fixture;

    #[test]
    fn a_row_per_band_then_every_pose() {
        let band = |from, to, poses, rms| Region {
            reach_from_mm: from,
            reach_to_mm: to,
            poses,
            rms_mm: rms,
            max_mm: 2.0 * rms,
        };
        let mut map = UncertaintyMap {
            coverage: 0.95,
            k_isotropic: 2.8,
            workspace: "sampled".into(),
            frame: None,
            tool: None,
            poses: 5,
            rms_mm: 0.05,
            median_mm: 0.04,
            max_mm: 0.1,
            regions: vec![band(0.0, 300.0, 2, 0.03), band(300.0, 600.0, 3, 0.06)],
            points: Vec::new(),
        };
        let t = uncertainty_map(&map, Some("/uncertainty_map"));
        assert!(
            t.contains("<caption>95 % radius per band of distance from the shoulder</caption>"),
            "{t}"
        );
        assert_eq!(fixture::rows(&t), 4, "{t}");
        assert!(
            t.contains(
                "<tr><td class=\"n\" data-json=\"/uncertainty_map/regions/1/reach_from_mm\" \
                 data-value=\"300.0\">300</td>"
            ),
            "{t}"
        );
        assert!(
            t.contains(
                "<tr class=\"after\"><td>all poses</td><td></td><td class=\"n\" \
                 data-json=\"/uncertainty_map/poses\" data-value=\"5.0\">5</td>"
            ),
            "{t}"
        );
        // A band has no median: a missing number in each.
        assert_eq!(t.matches("<td class=\"n\">-</td>").count(), 2, "{t}");
        map.frame = Some("laser <1>".into());
        assert!(
            uncertainty_map(&map, None)
                .contains(", in frame `laser &lt;1&gt;`, its registration included</caption>")
        );
    }
}
