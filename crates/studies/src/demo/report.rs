//! What the demo says: a short story of the run (what a terminal shows), the run and its
//! transitions as tables, the picture's data, and its files — `summary.json`, the learned
//! calculus and the MCAP log.

use serde_json::json;

use super::pipeline::BETA;
use super::{DemoConfig, DemoOutput, RUN_RULE};
use crate::report::{Attachment, Cell, Column, Figure, NavigationPicture, Plot, Report, Table};

/// The report of a demo run.
#[must_use]
pub fn report(config: &DemoConfig, o: &DemoOutput) -> Report {
    let mut attachments = vec![summary(config, o), o.log.clone()];
    if let Some(l) = &o.learned {
        attachments.push(l.spec.clone());
    }
    Report {
        title: format!("qrm demo (seed {})", config.seed),
        setup: story(config, o),
        tables: vec![run_table(config, o), transitions_table(o)],
        claims: Vec::new(),
        figures: vec![figure(o)],
        notes: String::new(),
        attachments,
    }
}

fn reached(o: &DemoOutput) -> &'static str {
    if o.run.outcome.success {
        "reached"
    } else {
        "not reached"
    }
}

/// Three lines: what was mapped and learned, how the navigation went and why this run, and
/// where to look.
fn story(config: &DemoConfig, o: &DemoOutput) -> String {
    let run = &o.run;
    let nav = &run.outcome;
    let learned = o.learned.as_ref().map_or(String::new(), |l| {
        format!("; SERGE learned a {}-state calculus", l.states)
    });
    let why = if nav.success {
        format!(
            "picked as the longest plan that succeeds ({} run(s) tried)",
            run.tried
        )
    } else {
        format!(
            "none of the {} start/goal pairs with a plan reaches its goal for seed {}: this is \
             the longest plan's run",
            run.tried, config.seed
        )
    };
    format!(
        "qrm demo (seed {}): mapped the field site by lidar alone ({} scans, {} landmarks, {} map \
         elements){learned}.\n\
         Q-Link to landmark {} with nothing but the qualitative map: {}, {} transitions planned, \
         {} re-plan(s), {:.0} m driven (Prop. 2 bound {:.0} m{}); {why}.\n\
         Files: demo.png (the run), run.mcap (Foxglove; layout docs/foxglove/qrm-layout.json), \
         summary.json.\n",
        config.seed,
        o.frames,
        o.recognised_landmarks,
        o.map_elements,
        run.goal,
        reached(o),
        nav.plan_len,
        nav.replans,
        nav.length,
        nav.bound,
        if config.nav_range < o.map_range {
            // Proposition 2 holds for a robot sensing at the mapping range R (§4.3.4)
            format!(", which assumes R' = R = {:.0} m", o.map_range)
        } else {
            String::new()
        },
    )
}

/// `summary.json`: the run in one JSON object (keys sorted), read by scripts and tests.
fn summary(config: &DemoConfig, o: &DemoOutput) -> Attachment {
    let nav = &o.run.outcome;
    let value = json!({
        "seed": config.seed,
        "scenario": "field",
        "frames": o.frames,
        "recognised_landmarks": o.recognised_landmarks,
        "map_elements": o.map_elements,
        "link_graph_edges": o.link_graph_edges,
        "beta": BETA,
        "learned_calculus_states": o.learned.as_ref().map(|l| l.states),
        "run_rule": RUN_RULE,
        "runs_tried": o.run.tried,
        "pairs_with_a_plan": o.run.candidates,
        "start": o.run.start,
        "goal": o.run.goal,
        "success": nav.success,
        "failure": nav.failure,
        "plan_len": nav.plan_len,
        "plan": nav.plan,
        "replans": nav.replans,
        "map_range": o.map_range,
        "sensor_range": config.nav_range,
        "robot": if config.exact_robot { json!("exact") } else { json!(config.navigating_robot()) },
        "trajectory_length": nav.length,
        "transit_length": nav.transit_length,
        "prop2_bound": nav.bound,
        "prop4_bound": nav.bound_direct,
        "transitions": nav.transitions,
    });
    Attachment::text(
        "summary.json",
        serde_json::to_string_pretty(&value).unwrap_or_default(),
    )
}

fn run_table(config: &DemoConfig, o: &DemoOutput) -> Table {
    let nav = &o.run.outcome;
    let mut t = Table::new(
        "run",
        "The run",
        vec![
            Column::new("quantity", "quantity"),
            Column::new("value", "value"),
        ],
    );
    let mut row = |what: &str, v: Cell| t.push(vec![Cell::text(what), v]);
    row("frames of the mapping drive", Cell::int(o.frames as u64));
    row(
        "landmarks recognised",
        Cell::int(o.recognised_landmarks as u64),
    );
    row("map elements", Cell::int(o.map_elements as u64));
    row(
        &format!("links (β = {BETA})"),
        Cell::int(o.link_graph_edges as u64),
    );
    row(
        "states of the learned calculus",
        Cell::maybe(o.learned.as_ref(), |l| Cell::int(l.states as u64)),
    );
    row(
        "start/goal pairs with a plan",
        Cell::int(o.run.candidates as u64),
    );
    row("runs tried", Cell::int(o.run.tried as u64));
    row("goal landmark", Cell::int(o.run.goal));
    row(
        "goal reached",
        Cell::text(if nav.success { "yes" } else { "no" }),
    );
    row("|P| (first plan)", Cell::int(nav.plan_len as u64));
    row("re-plans", Cell::int(nav.replans as u64));
    row("mapping range R (m)", Cell::fixed(o.map_range, 1));
    row("sensor range R' (m)", Cell::fixed(config.nav_range, 1));
    row("trajectory (m)", Cell::number(nav.length, 1));
    row("in transit (m)", Cell::number(nav.transit_length, 1));
    row(
        "Prop. 2 bound (2π + 1)·R·|P| (m)",
        Cell::number(nav.bound, 1),
    );
    row("Prop. 4 bound R·|P| (m)", Cell::number(nav.bound_direct, 1));
    t
}

fn transitions_table(o: &DemoOutput) -> Table {
    let mut t = Table::new(
        "transitions",
        "Transitions",
        vec![
            Column::new("from", "from element"),
            Column::new("to", "to element"),
            Column::new("link", "link landmark"),
            Column::new("success", "link found"),
            Column::new("length_m", "length (m)"),
        ],
    );
    for tr in &o.run.outcome.transitions {
        t.push(vec![
            Cell::int(tr.from as u64),
            Cell::int(tr.to as u64),
            Cell::int(tr.link),
            Cell::text(if tr.success { "yes" } else { "no" }),
            Cell::number(tr.length, 1),
        ]);
    }
    t
}

fn figure(o: &DemoOutput) -> Figure {
    let nav = &o.run.outcome;
    let p = &o.picture;
    Figure {
        name: "demo".into(),
        title: format!(
            "Q-Link to landmark {}: {}, |P| = {}, {:.0} m",
            o.run.goal,
            reached(o),
            nav.plan_len,
            nav.length
        ),
        x_label: "x (m)".into(),
        y_label: "y (m)".into(),
        plot: Plot::Navigation(Box::new(NavigationPicture {
            world: p.world.clone(),
            drive: p.drive.clone(),
            trajectory: nav.trajectory.clone(),
            searches: nav.searches.clone(),
            plan: p.plan.clone(),
            links: p.links.clone(),
            start: o.run.start,
            goal: p.goal,
            regions: p.regions.clone(),
        })),
    }
}
