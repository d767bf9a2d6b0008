from ursim_core.datasets import dataset_root
from ursim_core.matching import experiments as ex, MatchConfig, M_GRID
authors = {"00": 6, "01": 6, "03": 4, "04": 5, "06": 4, "07": 2, "08": 4, "10": 6, "11": 3, "12": 7, "14": 6, "15": 4, "17": 4, "18": 7, "20": 5, "21": 8, "23": 5, "24": 6}
for pl in ("released", "recommended"):
    c = ex.kth_pairs(dataset_root(), pipeline=pl)
    print(pl, "ours", {n: s.n_regions for n, s in c.sketches.items()}, "model", c.model.n_regions)
    if pl == "released":
        print("authors", authors, "model 6")
        s = ex.summarise(ex.f1_table(c, MatchConfig.released(), M_GRID, legacy="fnfix"))
        print("released oracle fnfix", s["malcolm"]["oracle"], s["vasiliki"]["oracle"])
    else:
        s = ex.summarise(ex.f1_table(c, MatchConfig()))
        print("default auto", s["malcolm"]["first"], s["vasiliki"]["first"])
