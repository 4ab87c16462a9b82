//! The registry: each [`ModeId`]'s entry, declared in the mode's own file,
//! and what is built on it (parameter checks, mode lists, constructors).

use std::collections::BTreeMap;

use super::culler::Culler;
use super::mode::{Candidacy, ModeError, ModeId, ModeInfo, ModeParams};
use crate::scene::Scene;

/// Declares [`ModeId::info`] from `mode_table!`'s lines (cull/mod.rs): an
/// exhaustive match onto each mode module's `MODE`.
macro_rules! declare_mode_entries {
    ($($id:ident => $name:literal, $($module:ident)::+;)*) => {
        impl ModeId {
            /// The mode's entry, declared in its own file.
            pub fn info(self) -> &'static ModeInfo {
                match self {
                    $(ModeId::$id => &super::$($module)::+::MODE,)*
                }
            }
        }
    };
}

mode_table!(declare_mode_entries);

impl ModeId {
    /// The mode's culler; scratch space is sized for `scene`, which each
    /// frame then brings in [`super::FrameInput`].
    pub fn create(self, scene: &Scene, params: &ModeParams) -> Result<Box<dyn Culler>, ModeError> {
        (self.info().build)(scene, params)
    }
}

impl ModeParams {
    /// Every mode's [`ModeInfo::exercised_with`]: the parameters that check
    /// a mode's exactness on every frame.
    pub fn exercising_every_frame() -> ModeParams {
        ModeId::ALL.iter().fold(ModeParams::default(), |params, &id| {
            id.info().exercised_with.iter().fold(params, |params, (key, value)| {
                params.with(&format!("{}.{key}", id.name()), value)
            })
        })
    }

    /// Parses `items` (`MODE.KEY=VALUE`) for a run of `modes`: each names a
    /// parameter of a mode that runs, or of one `auto` builds as a
    /// candidate where `auto` runs (it builds them with the run's
    /// parameters, so `--modes auto --param swr.threads=1` tunes its
    /// `swr`). Every value is parsed now.
    pub fn parse(items: &[String], modes: &[ModeId]) -> Result<ModeParams, ModeError> {
        let auto_runs = modes.contains(&ModeId::Auto);
        let candidates: Vec<ModeId> = auto_candidates().filter(|_| auto_runs).collect();
        let built: Vec<ModeId> = ModeId::ALL
            .iter()
            .copied()
            .filter(|m| modes.contains(m) || candidates.contains(m))
            .collect();
        let mut values = BTreeMap::new();
        for item in items {
            let (key, value) = item
                .split_once('=')
                .filter(|(k, _)| k.contains('.'))
                .ok_or_else(|| ModeError::MalformedParam(item.clone()))?;
            let (mode, name) = key.split_once('.').unwrap_or((key, ""));
            let info = mode
                .parse::<ModeId>()
                .ok()
                .filter(|m| built.contains(m))
                .map(ModeId::info);
            if !info.is_some_and(|m| m.params.iter().any(|p| p.key == name)) {
                let known = match info {
                    Some(m) if m.params.is_empty() => format!("{mode} takes no parameters"),
                    Some(m) => {
                        let keys: Vec<String> = m.params.iter().map(|p| format!("{mode}.{}", p.key)).collect();
                        format!("{mode} takes {}", keys.join(", "))
                    }
                    None if auto_runs => format!("mode '{mode}' is not being run, nor a candidate of auto"),
                    None => format!("mode '{mode}' is not being run"),
                };
                return Err(ModeError::UnknownParam {
                    key: key.to_string(),
                    known,
                });
            }
            if values.insert(key.to_string(), value.trim().to_string()).is_some() {
                return Err(ModeError::RepeatedParam(key.to_string()));
            }
        }
        let params = ModeParams { values };
        // Parse every typed value now, so a bad one is reported before a
        // long scene load rather than after it.
        for mode in built {
            (mode.info().check)(&params)?;
        }
        Ok(params)
    }
}

/// The modes `auto` may run, those whose entry allows it ([`Candidacy`]),
/// in [`ModeId::ALL`]'s order; which of them it runs, the adapter decides.
pub fn auto_candidates() -> impl Iterator<Item = ModeId> {
    ModeId::ALL
        .iter()
        .copied()
        .filter(|m| m.info().auto != Candidacy::Never)
}

/// A mode a run names that the adapter cannot run, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unrunnable {
    pub mode: ModeId,
    pub reason: String,
}

/// The modes of `runs` (each a mode and the parameters it is built with)
/// that the adapter cannot run (`unsupported` says why: its
/// [`ModeInfo::unsupported_on`]), each once; and the candidates of an
/// `auto` among them that the adapter cannot run and that were given
/// parameters: `auto` runs without them, which its summary's candidates
/// show, but a parameter given and not used is said so, not dropped
/// unsaid. The runs' own modes come first, so that a mode both run and
/// an `auto` candidate is skipped for itself, whatever the order of
/// `--modes`.
pub fn unrunnable(
    runs: &[(ModeId, &ModeParams)],
    unsupported: impl Fn(ModeId) -> Option<&'static str>,
) -> Vec<Unrunnable> {
    let mut skipped: Vec<Unrunnable> = Vec::new();
    let mut skip = |mode: ModeId, reason: String| {
        if !skipped.iter().any(|s| s.mode == mode) {
            skipped.push(Unrunnable { mode, reason });
        }
    };
    for &(mode, _) in runs {
        if let Some(reason) = unsupported(mode) {
            skip(mode, reason.to_string());
        }
    }
    for &(_, params) in runs.iter().filter(|(mode, _)| *mode == ModeId::Auto) {
        for candidate in auto_candidates() {
            let given: Vec<&str> = params.given_for(candidate).map(|(key, _)| key).collect();
            if let (Some(reason), false) = (unsupported(candidate), given.is_empty()) {
                let verb = if given.len() == 1 { "is" } else { "are" };
                let unused = given.join(", ");
                skip(
                    candidate,
                    format!("{reason}: auto runs without it, so {unused} {verb} not used"),
                );
            }
        }
    }
    skipped
}

/// Every mode's registry entry, in [`ModeId::ALL`]'s order.
pub fn modes() -> impl Iterator<Item = &'static ModeInfo> {
    ModeId::ALL.iter().map(|m| m.info())
}

/// The culler of the mode called `name` (see [`ModeId::create`]).
pub fn create(name: &str, scene: &Scene, params: &ModeParams) -> Result<Box<dyn Culler>, ModeError> {
    name.parse::<ModeId>()?.create(scene, params)
}

/// Parses a comma-separated mode list (`all` for every mode); duplicates are
/// dropped, the order kept.
pub fn parse_modes(list: &[String]) -> Result<Vec<ModeId>, ModeError> {
    let mut modes: Vec<ModeId> = Vec::new();
    for name in list.iter().flat_map(|s| s.split(',')).map(str::trim) {
        let found = if name == "all" {
            ModeId::ALL.to_vec()
        } else {
            vec![name.parse()?]
        };
        for m in found {
            if !modes.contains(&m) {
                modes.push(m);
            }
        }
    }
    if modes.is_empty() {
        return Err(ModeError::Empty);
    }
    Ok(modes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_values_that_exercise_every_frame_are_each_modes_own_parameters_and_parse() {
        let params = ModeParams::exercising_every_frame();
        for &id in ModeId::ALL {
            for (key, _) in id.info().exercised_with {
                assert!(
                    id.info().params.iter().any(|p| p.key == *key),
                    "{id}.{key} is no parameter of {id}"
                );
            }
            assert_eq!((id.info().check)(&params), Ok(()), "{id}'s exercising values");
        }
        let swr = crate::cull::swr::SwrParams::from_params(&params).unwrap();
        assert!(!swr.rests, "swr builds its buffer every frame");
    }

    #[test]
    fn a_value_set_over_the_exercising_ones_wins_and_the_others_stay() {
        // `occlu stress --param`.
        let given = ModeParams::parse(&["swr.rests=true".to_string()], &[ModeId::Swr]).unwrap();
        let over = ModeParams::exercising_every_frame().overridden_by(&given);
        assert!(crate::cull::swr::SwrParams::from_params(&over).unwrap().rests);
        assert_eq!(crate::cull::ChcParams::from_params(&over).unwrap().visible_for, 1);
    }

    #[test]
    fn an_auto_candidate_the_adapter_cannot_run_is_unrunnable_where_it_was_given_parameters() {
        let no_pixel_counts = |mode: ModeId| (mode == ModeId::Chc).then_some("no pixel counts");
        let given = ModeParams::default()
            .with("chc.visible_for", "3")
            .with("omq.batch", "8");
        let unrunnable_of = |runs: &[(ModeId, &ModeParams)]| -> Vec<(String, String)> {
            unrunnable(runs, no_pixel_counts)
                .into_iter()
                .map(|u| (u.mode.to_string(), u.reason))
                .collect()
        };
        // auto alone, chc given a parameter: chc is skipped, and why.
        assert_eq!(
            unrunnable_of(&[(ModeId::Auto, &given)]),
            [(
                "chc".to_string(),
                "no pixel counts: auto runs without it, so chc.visible_for is not used".to_string()
            )]
        );
        // Not given one, auto's summary says which candidates ran: no note.
        assert!(unrunnable_of(&[(ModeId::Auto, &ModeParams::default())]).is_empty());
        // Run itself too, chc is skipped once, for itself, in either order.
        let more = given.with("chc.r_split", "1");
        for both in [
            [(ModeId::Chc, &given), (ModeId::Auto, &more)],
            [(ModeId::Auto, &more), (ModeId::Chc, &given)],
        ] {
            assert_eq!(
                unrunnable_of(&both),
                [("chc".to_string(), "no pixel counts".to_string())]
            );
        }
        // Several parameters unused.
        assert_eq!(
            unrunnable_of(&[(ModeId::Auto, &more)])[0].1,
            "no pixel counts: auto runs without it, so chc.r_split, chc.visible_for are not used"
        );
    }

    #[test]
    fn every_entry_is_its_own_and_its_defaults_parse() {
        for &id in ModeId::ALL {
            assert_eq!(id.info().id, id, "{id}'s entry names another mode");
            assert_eq!(id.name().parse::<ModeId>(), Ok(id));
            assert_eq!((id.info().check)(&ModeParams::default()), Ok(()), "{id}'s defaults");
            let mut keys: Vec<&str> = id.info().params.iter().map(|p| p.key).collect();
            keys.sort_unstable();
            keys.dedup();
            assert_eq!(keys.len(), id.info().params.len(), "{id}'s parameter keys are unique");
        }
        let mut names: Vec<&str> = ModeId::ALL.iter().map(|m| m.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), ModeId::ALL.len(), "names are unique");
    }

    #[test]
    fn mode_lists_parse_in_order_without_duplicates() {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        assert_eq!(parse_modes(&s(&["vfc,dr", "vfc"])), Ok(vec![ModeId::Vfc, ModeId::Dr]));
        assert_eq!(parse_modes(&s(&["all"])), Ok(ModeId::ALL.to_vec()));
        assert_eq!(parse_modes(&s(&["dr,bogus"])), Err(ModeError::Unknown("bogus".into())));
        assert_eq!(parse_modes(&s(&[])), Err(ModeError::Empty));
        let listed = ModeError::Unknown("x".into()).to_string();
        let places: Vec<Option<usize>> = ModeId::ALL.iter().map(|m| listed.find(&format!(" {m},"))).collect();
        assert!(places.iter().all(Option::is_some), "every mode listed: {listed}");
        assert!(places.is_sorted(), "in the table's order: {listed}");
    }

    #[test]
    fn parameters_are_checked_against_the_running_modes() {
        let items = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let p = ModeParams::parse(&items(&["omq.om=80x60", "omq.factor=0.5"]), &[ModeId::Omq]).unwrap();
        assert_eq!(p.get(ModeId::Omq, ModeId::Omq.info().param("factor").unwrap()), Ok(0.5));
        assert_eq!(
            p.get(ModeId::Omq, ModeId::Omq.info().param("initial_max_tests").unwrap()),
            Ok(4u32)
        );
        let err = |v: &[&str], modes: &[ModeId]| ModeParams::parse(&items(v), modes).unwrap_err().to_string();
        assert!(err(&["omq.bogus=1"], &[ModeId::Omq]).contains("omq takes omq.om, omq.initial_max_tests, omq.factor"));
        assert!(err(&["omq.om=1x1"], &[ModeId::Vfc]).contains("'omq' is not being run"));
        assert!(err(&["vfc.x=1"], &[ModeId::Vfc]).contains("vfc takes no parameters"));
        assert!(err(&["omq"], &[ModeId::Omq]).contains("not MODE.KEY=VALUE"));
        assert!(
            err(&["omq.factor=fast"], &[ModeId::Omq]).contains("'fast'"),
            "values are parsed up front"
        );
        assert!(err(&["omq.factor=-1"], &[ModeId::Omq]).contains("positive"));
        // auto builds its candidates with the run's parameters: theirs are
        // taken, and checked, where it runs; a mode that is never one is
        // refused.
        let p = ModeParams::parse(&items(&["omq.factor=0.5"]), &[ModeId::Auto]).unwrap();
        assert_eq!(p.get(ModeId::Omq, ModeId::Omq.info().param("factor").unwrap()), Ok(0.5));
        assert!(err(&["omq.factor=-1"], &[ModeId::Auto]).contains("positive"));
        assert!(err(&["ac.x=1"], &[ModeId::Auto]).contains("'ac' is not being run, nor a candidate of auto"));
    }
}
